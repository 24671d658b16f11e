//! Prints EXR values for checks outside Rust (the browser test of report.html, tests/browser):
//!
//! ```text
//! exr_pixel pixel FILE.exr X Y                   → "R G B" of pixel (X, Y), from the top left
//! exr_pixel region IMAGE.exr REF.exr X0 Y0 X1 Y1 → "RMSE relMSE" of IMAGE against REF over
//!                                                  the pixels [X0, X1) × [Y0, Y1)
//! ```
//!
//! Values are printed in full (f32 values exactly, metrics to 17 significant digits); the
//! metrics are `dibench::metrics`' own, on the region cut out of both images.
//!
//! cargo build --release --example exr_pixel

use dibench::film::Image;
use dibench::output::read_exr;
use std::path::Path;

fn number(s: &str, what: &str) -> Result<u32, String> {
    s.parse()
        .map_err(|_| format!("{what}: `{s}` is not a pixel coordinate"))
}

fn load(path: &str) -> Result<Image, String> {
    read_exr(Path::new(path)).map_err(|e| e.to_string())
}

fn crop(img: &Image, x0: u32, y0: u32, x1: u32, y1: u32) -> Image {
    let pixels = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| img.pixels[(y * img.width + x) as usize]))
        .collect();
    Image {
        width: x1 - x0,
        height: y1 - y0,
        pixels,
    }
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let words: Vec<&str> = args.iter().map(String::as_str).collect();
    match words.as_slice() {
        ["pixel", file, x, y] => {
            let img = load(file)?;
            let (x, y) = (number(x, "X")?, number(y, "Y")?);
            if x >= img.width || y >= img.height {
                return Err(format!(
                    "({x}, {y}) is outside the {}×{} image",
                    img.width, img.height
                ));
            }
            let p = img.pixels[(y * img.width + x) as usize];
            // The values were f32 in the file: printed as f32, they are exact.
            println!("{} {} {}", p[0] as f32, p[1] as f32, p[2] as f32);
            Ok(())
        }
        ["region", image, reference, x0, y0, x1, y1] => {
            let (img, reference) = (load(image)?, load(reference)?);
            if (img.width, img.height) != (reference.width, reference.height) {
                return Err("the image and the reference differ in size".into());
            }
            let (x0, y0) = (number(x0, "X0")?, number(y0, "Y0")?);
            let (x1, y1) = (number(x1, "X1")?, number(y1, "Y1")?);
            if !(x0 < x1 && y0 < y1 && x1 <= img.width && y1 <= img.height) {
                return Err(format!(
                    "[{x0}, {x1}) × [{y0}, {y1}) is not a region of the {}×{} image",
                    img.width, img.height
                ));
            }
            let (a, b) = (crop(&img, x0, y0, x1, y1), crop(&reference, x0, y0, x1, y1));
            println!(
                "{:.17e} {:.17e}",
                dibench::metrics::rmse(&a, &b),
                dibench::metrics::relmse(&a, &b)
            );
            Ok(())
        }
        _ => Err(
            "usage: exr_pixel pixel FILE.exr X Y | exr_pixel region IMAGE.exr REF.exr \
                  X0 Y0 X1 Y1"
                .into(),
        ),
    }
}
