//! The input: a lat/long RGB EXR (see `latlong` for the orientation), read through `exr`.
//! Negative texels (ringing of lossy DWA compression next to the sun) are clamped to zero on
//! load; a non-finite texel is an error naming the file and the texel.

use super::latlong;
use crate::error::{Error, Result};
use crate::output::decode_exr;
use glam::Vec3;
use std::path::Path;

#[derive(Clone, Debug)]
pub struct LatLongImage {
    pub width: usize,
    pub height: usize,
    /// Row-major from the top row (+Y).
    pub pixels: Vec<Vec3>,
    /// How many texels had a negative channel clamped to zero on load.
    pub clamped: usize,
}

impl LatLongImage {
    /// Reads the first RGB(A) layer of the EXR file `path` (see [`Self::decode`]); the
    /// message names the file.
    pub fn load(path: &Path) -> std::result::Result<Self, String> {
        crate::bounded::read_file(path, 0)
            .and_then(|bytes| Self::decode(&bytes, path))
            .map_err(|e| e.to_string())
    }

    /// Decodes the first RGB(A) layer of the EXR `bytes` read from `path` (which errors name);
    /// the header's size is checked before pixel memory is allocated (`output::decode_exr`).
    pub fn decode(bytes: &[u8], path: &Path) -> Result<Self> {
        let (width, height, mut pixels) = decode_exr(bytes, path, Vec3::new)?;
        if width == 0 || height == 0 {
            return Err(Error::Parse {
                path: path.into(),
                message: "the image is empty".into(),
            });
        }
        let mut clamped = 0;
        for (k, p) in pixels.iter_mut().enumerate() {
            if !p.is_finite() {
                return Err(Error::Parse {
                    path: path.into(),
                    message: format!("texel ({}, {}) is not finite: {p}", k % width, k / width),
                });
            }
            if p.min_element() < 0.0 {
                *p = p.max(Vec3::ZERO);
                clamped += 1;
            }
        }
        Ok(LatLongImage {
            width,
            height,
            pixels,
            clamped,
        })
    }

    /// Nearest-texel radiance in direction `w` (the map's own piecewise-constant reconstruction).
    pub fn radiance(&self, w: Vec3) -> Vec3 {
        let [u, v] = latlong::dir_to_uv(w);
        let x = ((u * self.width as f32) as usize).min(self.width - 1);
        let y = ((v * self.height as f32) as usize).min(self.height - 1);
        self.pixels[y * self.width + x]
    }
}

/// Writes a lat/long image as a losslessly compressed (ZIP, scan-line, f32) EXR, atomically.
pub fn write_latlong(path: &Path, img: &LatLongImage) -> Result<()> {
    let film = crate::film::Image {
        width: img.width as u32,
        height: img.height as u32,
        pixels: img
            .pixels
            .iter()
            .map(|p| [p.x as f64, p.y as f64, p.z as f64])
            .collect(),
    };
    crate::output::write_exr(path, &film)
}
