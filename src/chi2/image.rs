//! The `dibench warp --png` picture: observed histogram beside the expected counts (the
//! integrated pdf) on the chart's (a, b) grid, one colour scale for both.

use super::Histogram;
use crate::error::{Error, Result};
use crate::output::write_atomic;
use std::path::Path;

const SCALE: usize = 4;
const GAP: usize = 8;

pub fn write_png(path: &Path, h: &Histogram) -> Result<()> {
    let max = h
        .observed
        .iter()
        .chain(&h.expected)
        .cloned()
        .fold(0.0f64, f64::max)
        .max(1e-12);
    let (cell_w, cell_h) = (SCALE, SCALE * 2);
    let (pw, ph) = (h.res_b * cell_w, h.res_a * cell_h);
    let width = 2 * pw + GAP;
    let mut rgb = vec![255u8; width * ph * 3];
    for (panel, data) in [&h.observed, &h.expected].into_iter().enumerate() {
        for i in 0..h.res_a {
            for j in 0..h.res_b {
                let c = colorous::VIRIDIS.eval_continuous(data[i * h.res_b + j] / max);
                for y in i * cell_h..(i + 1) * cell_h {
                    for x in j * cell_w..(j + 1) * cell_w {
                        let o = (y * width + panel * (pw + GAP) + x) * 3;
                        rgb[o..o + 3].copy_from_slice(&[c.r, c.g, c.b]);
                    }
                }
            }
        }
    }
    write_atomic(path, |file| {
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width as u32, ph as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let err = |e: png::EncodingError| Error::Output {
            path: path.into(),
            message: e.to_string(),
        };
        enc.write_header()
            .map_err(err)?
            .write_image_data(&rgb)
            .map_err(err)
    })
}
