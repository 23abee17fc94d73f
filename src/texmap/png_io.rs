//! PNG encoding of the maps (the `png` crate, its default compression: deterministic bytes) and
//! reading a map back.

use std::path::Path;

use super::{GrainMap, MapKind};
use crate::{Error, Result};

/// The largest map read back, in texels (16384², 1 GiB of 16-bit RGBA).
pub const MAX_MAP_TEXELS: usize = 1 << 28;

/// The channels of an encoded map.
#[derive(Clone, Copy, Debug)]
pub enum Channels {
    /// One grey channel.
    Grey,
    /// Red, green, blue.
    Rgb,
}

fn encode_error(e: png::EncodingError) -> Error {
    Error::Numerical { stage: "PNG encoding", message: e.to_string() }
}

fn encode(
    w: usize,
    h: usize,
    color: png::ColorType,
    depth: png::BitDepth,
    data: &[u8],
) -> Result<Vec<u8>> {
    let (Ok(pw), Ok(ph)) = (u32::try_from(w), u32::try_from(h)) else {
        return Err(Error::invalid_arg("map", format!("image {w} × {h} cannot be encoded")));
    };
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, pw, ph);
        enc.set_color(color);
        enc.set_depth(depth);
        let mut writer = enc.write_header().map_err(encode_error)?;
        writer.write_image_data(data).map_err(encode_error)?;
        writer.finish().map_err(encode_error)?;
    }
    Ok(out)
}

/// A 16-bit PNG of `w × h` pixels (rows top to bottom), samples as given.
pub fn encode16(w: usize, h: usize, channels: Channels, samples: &[u16]) -> Result<Vec<u8>> {
    let color = match channels {
        Channels::Grey => png::ColorType::Grayscale,
        Channels::Rgb => png::ColorType::Rgb,
    };
    // PNG stores 16-bit samples big-endian.
    let bytes: Vec<u8> = samples.iter().flat_map(|s| s.to_be_bytes()).collect();
    encode(w, h, color, png::BitDepth::Sixteen, &bytes)
}

/// Reads a grain map (docs/formats.md, "Grain maps"): a PNG of 8 or 16 bits per sample.
/// A direction map needs colour (RG; alpha and B are ignored); an angle map is grey (or its
/// red channel). Errors name the file.
pub fn read_map(path: &Path, kind: MapKind) -> Result<GrainMap> {
    let bad = |message: String| Error::Parse { path: path.to_path_buf(), line: 0, message };
    let file = std::fs::File::open(path).map_err(|e| bad(format!("cannot open: {e}")))?;
    let mut dec = png::Decoder::new(std::io::BufReader::new(file));
    dec.set_transformations(png::Transformations::EXPAND);
    let mut reader = dec.read_info().map_err(|e| bad(format!("not a PNG map: {e}")))?;
    let (w, h) = {
        let info = reader.info();
        (info.width as usize, info.height as usize)
    };
    if w == 0 || h == 0 || w.saturating_mul(h) > MAX_MAP_TEXELS {
        return Err(bad(format!("{w} × {h} texels: a map has 1 to {MAX_MAP_TEXELS} texels")));
    }
    let size = reader.output_buffer_size().ok_or_else(|| bad("too large".into()))?;
    let mut buf = vec![0; size];
    let out = reader.next_frame(&mut buf).map_err(|e| bad(format!("cannot decode: {e}")))?;
    let channels = out.color_type.samples();
    let sixteen = out.bit_depth == png::BitDepth::Sixteen;
    let sample = |k: usize| -> f64 {
        if sixteen {
            f64::from(u16::from_be_bytes([buf[2 * k], buf[2 * k + 1]])) / 65535.0
        } else {
            f64::from(buf[k]) / 255.0
        }
    };
    let line = out.line_size;
    let bytes_per = if sixteen { 2 } else { 1 };
    let texel = |i: usize, j: usize, c: usize| sample((j * line) / bytes_per + i * channels + c);
    let color = matches!(out.color_type, png::ColorType::Rgb | png::ColorType::Rgba);
    if kind == MapKind::Direction && !color {
        return Err(bad(format!(
            "a direction map needs colour (RG), this PNG is {:?}",
            out.color_type
        )));
    }
    let mut texels = Vec::with_capacity(w * h);
    for j in 0..h {
        for i in 0..w {
            texels.push(match kind {
                MapKind::Direction => {
                    [(2.0 * texel(i, j, 0) - 1.0) as f32, (2.0 * texel(i, j, 1) - 1.0) as f32]
                }
                MapKind::Angle => {
                    let a = texel(i, j, 0) * std::f64::consts::PI;
                    [a.cos() as f32, a.sin() as f32]
                }
            });
        }
    }
    Ok(GrainMap { kind, width: w, height: h, texels })
}
