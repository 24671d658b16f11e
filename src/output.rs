//! Everything dibench writes goes through here: to a temporary file in the target directory,
//! then renamed, so an interrupted run never leaves a half-written EXR, CSV or JSON.

use crate::error::{Error, Result};
use crate::film::Image as RgbImage;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Writes through `write` into `<path>.tmp-<pid>` and renames it over `path`.
pub fn write_atomic(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".tmp-{}", std::process::id()));
    let tmp = PathBuf::from(tmp);
    let result =
        write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e)));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| Error::io(path, e))
    })
}

pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::Output {
        path: path.into(),
        message: e.to_string(),
    })?;
    write_bytes(path, format!("{text}\n").as_bytes())
}

pub fn write_csv<T: Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(|e| Error::Output {
            path: path.into(),
            message: e.to_string(),
        })?;
    }
    let bytes = w.into_inner().map_err(|e| Error::Output {
        path: path.into(),
        message: e.to_string(),
    })?;
    write_bytes(path, &bytes)
}

/// RGB f32 EXR, ZIP-compressed scan lines (tiled files trip up some readers, e.g. tinyexr).
pub fn write_exr(path: &Path, img: &RgbImage) -> Result<()> {
    use exr::prelude::*;
    write_atomic(path, |tmp| {
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
            .to_file(tmp)
            .map_err(|e| crate::error::Error::Output {
                path: path.into(),
                message: format!("cannot write EXR: {e}"),
            })
    })
}

/// Reads the first RGB(A) layer of an EXR file.
pub fn read_exr(path: &Path) -> Result<RgbImage> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0.0f64; 3]; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<[f64; 3]>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r as f64, g as f64, b as f64];
        },
    )
    .map_err(|e| crate::error::Error::Parse {
        path: path.into(),
        message: format!("not a readable EXR image: {e}"),
    })?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok(RgbImage {
        width: size.width() as u32,
        height: size.height() as u32,
        pixels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exr_round_trip_is_exact_for_f32_values() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        let img = RgbImage {
            width: 3,
            height: 2,
            pixels: (0..6)
                .map(|i| [i as f64 * 0.25, 0.0009765625, 7.5e3])
                .collect(),
        };
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
}
