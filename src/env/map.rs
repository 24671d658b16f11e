//! The input: a lat/long RGB EXR (see `latlong` for the orientation), read through `exr`.
//! Negative texels (ringing of lossy DWA compression next to the sun) are clamped to zero on
//! load; a non-finite texel is an error naming the file and the texel.

use super::latlong;
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
    /// Reads the first RGB(A) layer of `path`; the message names the file.
    pub fn load(path: &Path) -> Result<Self, String> {
        use exr::prelude::*;
        let image = read_first_rgba_layer_from_file(
            path,
            |res, _| (res.width(), vec![Vec3::ZERO; res.width() * res.height()]),
            |(w, px): &mut (usize, Vec<Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
            },
        )
        .map_err(|e| format!("cannot read EXR {}: {e}", path.display()))?;
        let (width, mut pixels) = image.layer_data.channel_data.pixels;
        let height = pixels.len() / width.max(1);
        if width == 0 || height == 0 {
            return Err(format!("{}: the image is empty", path.display()));
        }
        let mut clamped = 0;
        for (k, p) in pixels.iter_mut().enumerate() {
            if !p.is_finite() {
                return Err(format!(
                    "{}: texel ({}, {}) is not finite: {p}",
                    path.display(),
                    k % width,
                    k / width
                ));
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
pub fn write_latlong(path: &Path, img: &LatLongImage) -> crate::error::Result<()> {
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
