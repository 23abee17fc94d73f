//! The glTF 2.0 binary container (glTF 2.0 spec, §4.4 "Binary glTF Layout"): a 12-byte header
//! (magic `glTF`, version 2, total length), a JSON chunk padded with spaces to 4 bytes, and a
//! BIN chunk padded with zeros to 4 bytes; every chunk is a little-endian length, a type and the
//! data.

/// `glTF` in ASCII, little-endian.
pub const MAGIC: u32 = 0x4654_6C67;
/// The JSON chunk's type, `JSON`.
pub const CHUNK_JSON: u32 = 0x4E4F_534A;
/// The BIN chunk's type, `BIN\0`.
pub const CHUNK_BIN: u32 = 0x004E_4942;

/// A growing binary buffer of 4-byte-aligned views.
#[derive(Clone, Debug, Default)]
pub struct Bin {
    /// The bytes.
    pub bytes: Vec<u8>,
}

impl Bin {
    /// Appends f32 values (little-endian) at a 4-byte boundary; returns (offset, length).
    pub fn push_f32(&mut self, values: impl IntoIterator<Item = f32>) -> (usize, usize) {
        self.align();
        let start = self.bytes.len();
        for v in values {
            self.bytes.extend_from_slice(&v.to_le_bytes());
        }
        (start, self.bytes.len() - start)
    }

    /// Appends u32 values (little-endian) at a 4-byte boundary; returns (offset, length).
    pub fn push_u32(&mut self, values: impl IntoIterator<Item = u32>) -> (usize, usize) {
        self.align();
        let start = self.bytes.len();
        for v in values {
            self.bytes.extend_from_slice(&v.to_le_bytes());
        }
        (start, self.bytes.len() - start)
    }

    /// Appends raw bytes (an embedded image) at a 4-byte boundary; returns (offset, length).
    pub fn push_bytes(&mut self, bytes: &[u8]) -> (usize, usize) {
        self.align();
        let start = self.bytes.len();
        self.bytes.extend_from_slice(bytes);
        (start, bytes.len())
    }

    fn align(&mut self) {
        let pad = (4 - self.bytes.len() % 4) % 4;
        self.bytes.resize(self.bytes.len() + pad, 0);
    }
}

/// The .glb bytes of a JSON document and its binary buffer.
pub fn container(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |n: usize| (4 - n % 4) % 4;
    let json_len = json.len() + pad(json.len());
    let bin_len = bin.len() + pad(bin.len());
    let total = 12 + 8 + json_len + if bin.is_empty() { 0 } else { 8 + bin_len };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(&MAGIC.to_le_bytes());
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json_len as u32).to_le_bytes());
    out.extend_from_slice(&CHUNK_JSON.to_le_bytes());
    out.extend_from_slice(json);
    out.resize(out.len() + pad(json.len()), b' ');
    if !bin.is_empty() {
        out.extend_from_slice(&(bin_len as u32).to_le_bytes());
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        out.extend_from_slice(bin);
        out.resize(out.len() + pad(bin.len()), 0);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The layout by hand: "{}" padded to 4 with two spaces, 3 BIN bytes padded with one zero.
    #[test]
    fn layout() {
        let g = container(b"{}", &[1, 2, 3]);
        assert_eq!(&g[0..4], b"glTF");
        assert_eq!(u32::from_le_bytes(g[4..8].try_into().unwrap()), 2);
        assert_eq!(u32::from_le_bytes(g[8..12].try_into().unwrap()) as usize, g.len());
        assert_eq!(g.len(), 12 + 8 + 4 + 8 + 4);
        assert_eq!(&g[16..20], b"JSON");
        assert_eq!(&g[20..24], b"{}  ");
        assert_eq!(&g[28..32], b"BIN\0");
        assert_eq!(&g[32..36], &[1, 2, 3, 0]);
    }
}
