//! RGB EXR files: written as f32 scan lines, read with the header checked before any pixel
//! memory is allocated (a header may claim any size).

use crate::bounded;
use crate::error::{Error as DibenchError, Result};
use crate::film::Image as RgbImage;
use std::io::Cursor;
use std::path::Path;

/// RGB f32 EXR, ZIP-compressed scan lines (tiled files trip up some readers, e.g. tinyexr),
/// written atomically.
pub fn write_exr(path: &Path, img: &RgbImage) -> Result<()> {
    super::write_atomic(path, |tmp| encode_exr(tmp, img, path))
}

/// Writes `img` as an EXR to the file `to` directly (errors name `named`): for writers that
/// already write to a temporary file, such as a store commit.
pub fn encode_exr(to: &Path, img: &RgbImage, named: &Path) -> Result<()> {
    use exr::prelude::*;
    {
        let w = img.width as usize;
        let enc = Encoding {
            compression: Compression::ZIP16,
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        };
        let layer = Layer::new(
            (w, img.height as usize),
            LayerAttributes::default(),
            enc,
            SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                let p = img.pixels[y * w + x];
                (p[0] as f32, p[1] as f32, p[2] as f32)
            }),
        );
        exr::image::Image::from_layer(layer)
            .write()
            .to_file(to)
            .map_err(|e| DibenchError::Output {
                path: named.into(),
                message: format!("cannot write EXR: {e}"),
            })
    }
}

/// Reads the first RGB(A) layer of an EXR file (a regular file, its size and then its header
/// checked before decoding).
pub fn read_exr(path: &Path) -> Result<RgbImage> {
    let bytes = bounded::read_file(path, 0)?;
    let (width, height, pixels) =
        decode_exr(&bytes, path, |r, g, b| [r as f64, g as f64, b as f64])?;
    Ok(RgbImage {
        width: width as u32,
        height: height as u32,
        pixels,
    })
}

/// Decodes the first RGB(A) layer of the EXR `bytes` (read from `path`, which errors name)
/// into row-major pixels made by `pixel`: (width, height, pixels). Before anything is
/// allocated for pixels, every header's block count is checked against the bytes there are
/// (each block needs an 8-byte offset), and the largest layer against available memory.
pub fn decode_exr<T: Clone + Default + 'static>(
    bytes: &[u8],
    path: &Path,
    pixel: fn(f32, f32, f32) -> T,
) -> Result<(usize, usize, Vec<T>)> {
    use exr::prelude::*;
    let unreadable = |e: exr::error::Error| DibenchError::Parse {
        path: path.into(),
        message: format!("not a readable EXR image: {e}"),
    };
    let meta =
        exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(unreadable)?;
    let mut largest = 0u64;
    let mut blocks = 0u64;
    for h in meta.headers.iter() {
        let (w, hgt) = (h.layer_size.width() as u64, h.layer_size.height() as u64);
        blocks = blocks.saturating_add(h.chunk_count as u64);
        if bounded::bytes(blocks, 8) > bytes.len() as u64 {
            return Err(DibenchError::Parse {
                path: path.into(),
                message: format!(
                    "the header claims {w}×{hgt} pixels in {} blocks, more than the file's {} \
                     bytes can hold (truncated or damaged)",
                    h.chunk_count,
                    bytes.len()
                ),
            });
        }
        largest = largest.max(w.saturating_mul(hgt));
    }
    // The pixels as built here, plus the decoder's f32 samples of the layer.
    let per_pixel = std::mem::size_of::<T>() as u64 + 16;
    bounded::check_memory(
        || format!("{}: an EXR of {largest} pixels", path.display()),
        bounded::bytes(largest, per_pixel),
    )?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res, _| (res.width(), vec![T::default(); res.width() * res.height()]),
            move |(w, px): &mut (usize, Vec<T>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = pixel(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(unreadable)?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok((size.width(), size.height(), pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32) -> RgbImage {
        RgbImage {
            width: w,
            height: h,
            pixels: (0..w * h)
                .map(|i| [i as f64 * 0.25, 0.0009765625, 7.5e3])
                .collect(),
        }
    }

    #[test]
    fn exr_round_trip_is_exact_for_f32_values() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        let img = image(3, 2);
        write_exr(&path, &img).unwrap();
        assert_eq!(read_exr(&path).unwrap(), img);
        let leftovers: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(
            leftovers.len(),
            1,
            "temporary files left behind: {leftovers:?}"
        );
    }

    #[test]
    fn truncated_exr_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.exr");
        std::fs::write(&path, b"v/1\x01\x02\x00\x00").unwrap();
        let err = read_exr(&path).unwrap_err().to_string();
        assert!(err.contains("bad.exr"), "{err}");
    }

    /// A header whose data window claims 2^29 rows (EXR allows up to 2^30) is refused before
    /// any pixel memory is allocated; the same file with its true size reads.
    #[test]
    fn a_header_claiming_more_than_the_file_holds_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("liar.exr");
        write_exr(&path, &image(4, 4)).unwrap();
        let mut bytes = std::fs::read(&path).unwrap();
        assert!(decode_exr(&bytes, &path, |r, _, _| r).is_ok());
        // dataWindow is a box2i: xMin, yMin, xMax, yMax after its name, type and size.
        let at = bytes.windows(10).position(|w| w == b"dataWindow").unwrap();
        let y_max = at + b"dataWindow\0box2i\0".len() + 4 + 12;
        bytes[y_max..y_max + 4].copy_from_slice(&(1i32 << 29).to_le_bytes());
        let msg = decode_exr(&bytes, &path, |r, _, _| r)
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("liar.exr") && msg.contains("more than the file"),
            "{msg}"
        );
    }
}
