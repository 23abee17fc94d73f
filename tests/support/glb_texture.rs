//! A grainline glb read as a viewer reads its material's textures: the JSON chunk, an embedded
//! 16-bit RGB PNG decoded with RG mapped back to [−1, 1] (docs/gltf.md), and glTF's bilinear
//! sampler with clamp-to-edge. Shared by the tests that read the anisotropy texture back
//! (tests/gltf_export.rs, tests/brushed_outside.rs, tests/support/cad_truth.rs).

use serde_json::Value;

/// A texture decoded: RG mapped to [−1, 1], rows top to bottom.
pub struct Texture {
    /// Width and height, texels.
    pub size: usize,
    /// Per texel, row by row.
    pub rg: Vec<[f64; 2]>,
    /// Per texel, B in [0, 1]: the anisotropy strength.
    pub b: Vec<f64>,
}

impl Texture {
    /// Bilinear between the four nearest texel centres at glTF texture coordinates `st`,
    /// clamped to the edge (the file's sampler).
    pub fn sample(&self, st: [f64; 2]) -> [f64; 2] {
        let mut out = [0.0; 2];
        for (k, w) in self.bilinear(st) {
            out[0] += w * self.rg[k][0];
            out[1] += w * self.rg[k][1];
        }
        out
    }

    /// The strength (B) at `st`, sampled as [`Texture::sample`] samples RG.
    pub fn sample_strength(&self, st: [f64; 2]) -> f64 {
        self.bilinear(st).into_iter().map(|(k, w)| w * self.b[k]).sum()
    }

    /// The four texels glTF's bilinear sampler reads at `st` (clamped), with their weights.
    fn bilinear(&self, st: [f64; 2]) -> [(usize, f64); 4] {
        let n = self.size as f64;
        let x = (st[0] * n - 0.5).clamp(0.0, n - 1.0);
        let y = (st[1] * n - 0.5).clamp(0.0, n - 1.0);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(self.size - 1), (y0 + 1).min(self.size - 1));
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let at = |i: usize, j: usize| j * self.size + i;
        [
            (at(x0, y0), (1.0 - fx) * (1.0 - fy)),
            (at(x1, y0), fx * (1.0 - fy)),
            (at(x0, y1), (1.0 - fx) * fy),
            (at(x1, y1), fx * fy),
        ]
    }
}

/// The glb's JSON chunk.
pub fn glb_json(bytes: &[u8]) -> Value {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

/// The embedded PNG of texture `index` (16-bit RGB, square), decoded.
pub fn read_texture(doc: &Value, blob: &[u8], index: usize) -> Texture {
    let image = &doc["images"][doc["textures"][index]["source"].as_u64().unwrap() as usize];
    assert_eq!(image["mimeType"], "image/png");
    let view = &doc["bufferViews"][image["bufferView"].as_u64().unwrap() as usize];
    let off = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    let len = view["byteLength"].as_u64().unwrap() as usize;
    let mut reader =
        png::Decoder::new(std::io::Cursor::new(&blob[off..off + len])).read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.color_type, info.bit_depth), (png::ColorType::Rgb, png::BitDepth::Sixteen));
    assert_eq!(info.width, info.height);
    let size = info.width as usize;
    let c = |p: &[u8], o: usize| f64::from(u16::from_be_bytes([p[o], p[o + 1]])) / 65535.0;
    let rg = buf[..6 * size * size]
        .chunks(6)
        .map(|p| [2.0 * c(p, 0) - 1.0, 2.0 * c(p, 2) - 1.0])
        .collect();
    let b = buf[..6 * size * size].chunks(6).map(|p| c(p, 4)).collect();
    Texture { size, rg, b }
}
