//! Re-encodes a lat/long EXR losslessly for committing: negative texels (DWA ringing) clamped
//! to zero, RGB half floats (the inputs are half floats, so nothing else changes), ZIP
//! scan lines. Used by scripts/fetch-envmaps.sh.
//!
//! cargo run --release --example reencode_envmap -- IN.exr OUT.exr

use dibench::env::map::LatLongImage;
use exr::prelude::*;
use std::path::Path;

fn main() -> std::result::Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [input, output] = args.as_slice() else {
        return Err("usage: reencode_envmap IN.exr OUT.exr".into());
    };
    let img = LatLongImage::load(Path::new(input))?;
    let w = img.width;
    let enc = Encoding {
        compression: Compression::ZIP16,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let layer = Layer::new(
        (w, img.height),
        LayerAttributes::default(),
        enc,
        SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let p = img.pixels[y * w + x];
            (f16::from_f32(p.x), f16::from_f32(p.y), f16::from_f32(p.z))
        }),
    );
    let tmp = format!("{output}.tmp");
    Image::from_layer(layer)
        .write()
        .to_file(&tmp)
        .map_err(|e| format!("cannot write {tmp}: {e}"))?;
    std::fs::rename(&tmp, output).map_err(|e| format!("cannot rename to {output}: {e}"))?;
    let max = img
        .pixels
        .iter()
        .map(|p| p.max_element())
        .fold(0.0f32, f32::max);
    let mean: f64 = img
        .pixels
        .iter()
        .map(|p| p.x as f64 + p.y as f64 + p.z as f64)
        .sum::<f64>()
        / (3 * img.pixels.len()) as f64;
    println!(
        "{output}: {}x{}, {} texels clamped, max {max:.1}, mean {mean:.3}",
        img.width, img.height, img.clamped
    );
    Ok(())
}
