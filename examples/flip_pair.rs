//! FLIP of one image pair, for `scripts/flip-check.py`: reads two raw images, writes the map.
//!
//! `cargo run --release --example flip_pair -- <ldr|ldr-linear|hdr> REF TEST OUT [PPD]`
//! `cargo run --release --example flip_pair -- convert IN.exr OUT.raw` (an EXR to a raw image)
//!
//! Raw image files: little-endian u32 width, u32 height, then width·height·3 f32 (RGB,
//! scan-line order). The output has the same header and width·height f32. One line on stdout:
//! `mean=<f64> start=<f32> stop=<f32> count=<u32>` (exposures for `hdr` only).

use dibench::flip;
use std::io::Write;
use std::process::ExitCode;

fn read_raw(path: &str) -> Result<(usize, usize, Vec<[f32; 3]>), String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
    if bytes.len() < 8 {
        return Err(format!("{path}: shorter than its header"));
    }
    let w = u32::from_le_bytes(bytes[0..4].try_into().unwrap()) as usize;
    let h = u32::from_le_bytes(bytes[4..8].try_into().unwrap()) as usize;
    let body = &bytes[8..];
    if body.len() != w * h * 12 {
        return Err(format!(
            "{path}: {w}×{h} needs {} bytes after the header, has {}",
            w * h * 12,
            body.len()
        ));
    }
    let px = body
        .chunks_exact(12)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes(c[4 * i..4 * i + 4].try_into().unwrap());
            [f(0), f(1), f(2)]
        })
        .collect();
    Ok((w, h, px))
}

fn write_raw(path: &str, width: usize, height: usize, values: &[f32]) -> Result<(), String> {
    let mut bytes = Vec::with_capacity(8 + 4 * values.len());
    bytes.extend_from_slice(&(width as u32).to_le_bytes());
    bytes.extend_from_slice(&(height as u32).to_le_bytes());
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes).map_err(|e| format!("{path}: {e}"))
}

fn run(args: &[String]) -> Result<(), String> {
    if let [mode, input, out] = args
        && mode == "convert"
    {
        let img = dibench::output::read_exr(input.as_ref()).map_err(|e| e.to_string())?;
        let values: Vec<f32> = img.pixels.iter().flatten().map(|&v| v as f32).collect();
        return write_raw(out, img.width as usize, img.height as usize, &values);
    }
    let [mode, reference, test, out, rest @ ..] = args else {
        return Err(
            "usage: flip_pair <ldr|ldr-linear|hdr> REF TEST OUT [PPD] | convert IN.exr OUT.raw"
                .into(),
        );
    };
    let ppd = match rest.first() {
        Some(s) => s.parse::<f32>().map_err(|e| format!("PPD {s}: {e}"))?,
        None => flip::DEFAULT_PPD,
    };
    let (w, h, r) = read_raw(reference)?;
    let (tw, th, t) = read_raw(test)?;
    if (w, h) != (tw, th) {
        return Err(format!("sizes differ: {w}×{h} and {tw}×{th}"));
    }
    let (map, exposures) = match mode.as_str() {
        "ldr" => (flip::ldr_flip(&r, &t, w, h, ppd), None),
        "ldr-linear" => (flip::ldr_flip_linear(&r, &t, w, h, ppd), None),
        "hdr" => match flip::hdr_flip_with(&r, &t, w, h, ppd, None) {
            Ok(f) => (Ok(f.map), Some(f.exposures)),
            Err(e) => (Err(e), None),
        },
        m => return Err(format!("unknown mode {m}")),
    };
    let map = map.map_err(|e| e.to_string())?;
    write_raw(out, w, h, &map.values)?;
    let mut line = format!("mean={:.9}", map.mean());
    if let Some(e) = exposures {
        line += &format!(" start={:.9} stop={:.9} count={}", e.start, e.stop, e.count);
    }
    writeln!(std::io::stdout(), "{line}").map_err(|e| e.to_string())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("flip_pair: {e}");
            ExitCode::FAILURE
        }
    }
}
