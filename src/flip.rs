//! FLIP, the perceptual image-difference evaluator of Andersson et al., "FLIP: A Difference
//! Evaluator for Alternating Images" (HPG 2020), and its HDR extension, "Visualizing Errors in
//! Rendered High Dynamic Range Images" (Eurographics 2021).
//!
//! This is a port of NVIDIA's reference implementation (`FLIP.h` of github.com/NVlabs/flip,
//! the code of the `flip-evaluator` 1.7 Python package), operation for operation
//! in f32 so that the maps agree with it to float rounding: the same constants, the same
//! separable filters with the same radii and normalisations, clamp-to-edge borders, the same
//! order of additions. `docs/flip.md` has the measured agreement (`scripts/flip-check.py`).
//!
//! Entry points:
//! - [`ldr_flip`]: LDR-FLIP of two **sRGB-encoded** images with values in [0, 1] (what a PNG
//!   holds), as `flip_evaluator.evaluate(ref, test, "LDR")` with its default `inputsRGB=True`.
//!   [`ldr_flip_linear`] takes linear RGB in [0, 1] instead. Values outside [0, 1] are clamped.
//! - [`hdr_flip`]: HDR-FLIP of two **linear** radiance images (non-negative, any range), as
//!   `flip_evaluator.evaluate(ref, test, "HDR")`: start and stop exposures from the reference,
//!   the reference implementation's ACES fit as tone map, LDR-FLIP at each exposure, the
//!   per-pixel maximum. [`hdr_flip_with`] takes explicit exposures; [`hdr_flip_image`] takes the
//!   crate's [`Image`] (linear radiance, f64) at the default viewing condition.
//!
//! Every map value lies in [0, 1]; 0 means no perceived difference. LDR-FLIP treats its two
//! images alike (HyAB and the feature term |f(ref) − f(test)| are symmetric), so swapping them
//! gives the same map, bit for bit. HDR-FLIP is not symmetric: the reference alone sets the
//! exposures.
//!
//! Where this port differs from the reference (only where the reference gives no number):
//! - non-finite input values are rejected with an error;
//! - HDR: the reference's median luminance is floored at f32::EPSILON (as flip-evaluator 1.7
//!   does; 1.6 gave an infinite stop exposure when more than half the pixels are black), and
//!   here its maximum luminance too: the reference exits on an all-black reference (start
//!   exposure ∞ > stop), this port uses start = stop = log₂(0.85-point / ε) ≈ 24.1. An exposure
//!   whose log₂ overflows f32 (a luminance above ~1e38) is computed in f64;
//! - HDR: the ACES fit is evaluated, for |c| > 1e18, divided through by c², so a huge exposed
//!   value (the reference's form squares it to ∞ and gives ∞/∞ = NaN) gets the fit's limit;
//!   explicit exposures above 127 stops (2^e not a finite f32) are refused;
//! - a filter whose derivative weights all underflow (pixels per degree below about 1.7)
//!   gets zero derivative weights instead of 0/0 = NaN.

use crate::error::{Error, Result};
use crate::film::Image;
use rayon::prelude::*;

type C3 = [f32; 3];

/// The reference's π, `3.14159265358979f`: the same f32 as `std::f32::consts::PI`.
const PI: f32 = std::f32::consts::PI;
const PI_SQ: f32 = PI * PI;

/// Pixels per degree of visual angle for a viewer `distance` metres from a monitor `width_m`
/// metres wide showing `width_px` pixels across (the reference's `calculatePPD`).
pub const fn pixels_per_degree(distance: f32, width_px: f32, width_m: f32) -> f32 {
    distance * (width_px / width_m) * (PI / 180.0)
}

/// The reference implementation's default viewing condition: 0.7 m from a 0.7 m wide monitor
/// with 3840 pixels across, 67.02 pixels per degree (not exactly 67).
pub const DEFAULT_PPD: f32 = pixels_per_degree(0.7, 3840.0, 0.7);

/// A FLIP error map: one value in [0, 1] per pixel, scan-line order.
#[derive(Clone, Debug, PartialEq)]
pub struct FlipMap {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f32>,
}

impl FlipMap {
    /// Mean FLIP over the pixels, accumulated in f64 (0 for an empty map).
    pub fn mean(&self) -> f64 {
        if self.values.is_empty() {
            return 0.0;
        }
        self.values.iter().map(|&v| v as f64).sum::<f64>() / self.values.len() as f64
    }

    /// Largest per-pixel value (0 for an empty map).
    pub fn max(&self) -> f32 {
        self.values.iter().copied().fold(0.0, f32::max)
    }

    pub fn get(&self, x: usize, y: usize) -> f32 {
        self.values[y * self.width + x]
    }

    /// The map as an image, the value in all three channels (an error map EXR viewers show
    /// in grey, `<stem>.flip.exr`).
    pub fn to_image(&self) -> Image {
        Image {
            width: self.width as u32,
            height: self.height as u32,
            pixels: self.values.iter().map(|&v| [v as f64; 3]).collect(),
        }
    }
}

/// HDR-FLIP's peak working memory in units of an f64 RGB image (24 bytes per pixel), for
/// callers that check memory before rendering: the two f32 inputs, their tone-mapped,
/// YCxCz, filtered L*a*b* and feature images, and the maps come to about 160 bytes per
/// pixel; 8 × 24 = 192 bounds it.
pub const WORKING_IMAGES: u64 = 8;

/// What a FLIP map's EXR holds (`Provenance::content`).
pub const CONTENT: &str = "HDR-FLIP error";

/// HDR-FLIP's exposures, in stops (the image is multiplied by 2^exposure).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exposures {
    pub start: f32,
    pub stop: f32,
    /// At least 2; the exposures are `start + i·(stop − start)/(count − 1)`.
    pub count: u32,
}

/// HDR-FLIP's result: the map and the exposures it used.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrFlip {
    pub map: FlipMap,
    pub exposures: Exposures,
}

// ---------------------------------------------------------------------------------------------
// Colour spaces (FLIP.h, class color3). Constants keep the reference's digits (more than f32
// holds; the literals round to the same f32 as the reference's).

#[allow(clippy::excessive_precision)]
const ILLUMINANT: C3 = [0.950_428_545, 1.0, 1.088_900_371];
#[allow(clippy::excessive_precision)]
const INV_ILLUMINANT: C3 = [1.052_156_925, 1.0, 0.918_357_670];

fn srgb_to_linear(s: f32) -> f32 {
    if s <= 0.04045 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_rgb_to_xyz(c: C3) -> C3 {
    const A11: f32 = 10135552.0 / 24577794.0;
    const A12: f32 = 8788810.0 / 24577794.0;
    const A13: f32 = 4435075.0 / 24577794.0;
    const A21: f32 = 2613072.0 / 12288897.0;
    const A22: f32 = 8788810.0 / 12288897.0;
    const A23: f32 = 887015.0 / 12288897.0;
    const A31: f32 = 1425312.0 / 73733382.0;
    const A32: f32 = 8788810.0 / 73733382.0;
    const A33: f32 = 70074185.0 / 73733382.0;
    [
        A11 * c[0] + A12 * c[1] + A13 * c[2],
        A21 * c[0] + A22 * c[1] + A23 * c[2],
        A31 * c[0] + A32 * c[1] + A33 * c[2],
    ]
}

#[allow(clippy::excessive_precision)]
fn xyz_to_linear_rgb(c: C3) -> C3 {
    [
        3.241_003_275 * c[0] + -1.537_398_934 * c[1] + -0.498_615_861 * c[2],
        -0.969_224_334 * c[0] + 1.875_930_071 * c[1] + 0.041_554_224 * c[2],
        0.055_639_423 * c[0] + -0.204_011_202 * c[1] + 1.057_148_933 * c[2],
    ]
}

fn xyz_to_cielab(c: C3) -> C3 {
    const DELTA: f32 = 6.0 / 29.0;
    const DELTA_SQ: f32 = DELTA * DELTA;
    const DELTA_CUBE: f32 = DELTA * DELTA_SQ;
    const FACTOR: f32 = 1.0 / (3.0 * DELTA_SQ);
    const TERM: f32 = 4.0 / 29.0;
    let f = |t: f32| {
        if t > DELTA_CUBE {
            t.powf(1.0 / 3.0)
        } else {
            FACTOR * t + TERM
        }
    };
    let x = f(c[0] * INV_ILLUMINANT[0]);
    let y = f(c[1] * INV_ILLUMINANT[1]);
    let z = f(c[2] * INV_ILLUMINANT[2]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn xyz_to_ycxcz(c: C3) -> C3 {
    let x = c[0] * INV_ILLUMINANT[0];
    let y = c[1] * INV_ILLUMINANT[1];
    let z = c[2] * INV_ILLUMINANT[2];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz(c: C3) -> C3 {
    let y = (c[0] + 16.0) / 116.0;
    let cx = c[1] / 500.0;
    let cz = c[2] / 200.0;
    let x = y + cx;
    let z = y - cz;
    [x * ILLUMINANT[0], y * ILLUMINANT[1], z * ILLUMINANT[2]]
}

fn clamp01(c: C3) -> C3 {
    c.map(|v| v.clamp(0.0, 1.0))
}

fn luminance(c: C3) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// CIELab with the Hunt adjustment of the chroma (a, b scaled by 0.01·L).
fn hunt_lab(linear_rgb: C3) -> C3 {
    let lab = xyz_to_cielab(linear_rgb_to_xyz(linear_rgb));
    [lab[0], 0.01 * lab[0] * lab[1], 0.01 * lab[0] * lab[2]]
}

/// HyAB distance: city-block in L, Euclidean in (a, b).
fn hyab(r: C3, t: C3) -> f32 {
    let dl = (r[0] - t[0]).abs();
    let da = r[1] - t[1];
    let db = r[2] - t[2];
    dl + (da * da + db * db).sqrt()
}

// FLIP's constants (FLIP.h, FLIPConstants).
const GQC: f32 = 0.7;
const GPC: f32 = 0.4;
const GPT: f32 = 0.95;
const GW: f32 = 0.082;
const GQF: f32 = 0.5;

/// The largest colour difference, between pure green and pure blue, to the power `GQC`.
fn max_distance() -> f32 {
    hyab(hunt_lab([0.0, 1.0, 0.0]), hunt_lab([0.0, 0.0, 1.0])).powf(GQC)
}

// ---------------------------------------------------------------------------------------------
// Filters (FLIP.h: Gaussian, GaussianSqrt, calculateSpatialFilterRadius, setSpatialFilters,
// setFeatureFilter). See misc/separatedConvolutions.pdf of the reference repository.

// Contrast sensitivity Gaussians: a1, b1 for Y, Cx, Cz; a2, b2 (second Gaussian of Cz).
const A1: C3 = [1.0, 1.0, 34.1];
const B1: C3 = [0.0047, 0.0053, 0.04];
const A2Z: f32 = 13.5;
const B2: C3 = [1.0e-5, 1.0e-5, 0.025];

fn gaussian_ab(x2: f32, a: f32, b: f32) -> f32 {
    a * (PI / b).sqrt() * (-PI_SQ * x2 / b).exp()
}

fn gaussian_ab_sqrt(x2: f32, a: f32, b: f32) -> f32 {
    (a * (PI / b).sqrt()).sqrt() * (-PI_SQ * x2 / b).exp()
}

/// Radius of the spatial (contrast sensitivity) filters: three standard deviations of the
/// widest Gaussian, `ceil(3·sqrt(b_max / (2π²))·ppd)`; 10 at the default 67.02 ppd.
pub fn spatial_filter_radius(ppd: f32) -> usize {
    let b_max = B1[0].max(B1[1]).max(B1[2].max(B2[0])).max(B2[1].max(B2[2]));
    (3.0 * (b_max / (2.0 * PI_SQ)).sqrt() * ppd).ceil() as usize
}

/// Standard deviation, in pixels, of the feature (edge and point) detection Gaussian.
fn feature_std_dev(ppd: f32) -> f32 {
    0.5 * GW * ppd
}

/// Radius of the feature filters, `ceil(3σ)` with σ = 0.5·0.082·ppd; 9 at 67.02 ppd.
pub fn feature_filter_radius(ppd: f32) -> usize {
    (3.0 * feature_std_dev(ppd)).ceil() as usize
}

/// Weights of the separated spatial filters: `[Y, Cx]` (normalised to sum 1 each) and the two
/// square-rooted Gaussians of Cz (normalised together).
fn spatial_filters(ppd: f32) -> (Vec<[f32; 2]>, Vec<[f32; 2]>) {
    let radius = spatial_filter_radius(ppd) as i64;
    let delta_x = 1.0 / ppd;
    let mut ycx = Vec::new();
    let mut cz = Vec::new();
    let (mut sum_y, mut sum_cx, mut sum_cz1, mut sum_cz2) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    for x in -radius..=radius {
        let ix = x as f32 * delta_x;
        let ix2 = ix * ix;
        let g_y = gaussian_ab(ix2, A1[0], B1[0]);
        let g_cx = gaussian_ab(ix2, A1[1], B1[1]);
        let g_cz1 = gaussian_ab_sqrt(ix2, A1[2], B1[2]);
        let g_cz2 = gaussian_ab_sqrt(ix2, A2Z, B2[2]);
        ycx.push([g_y, g_cx]);
        cz.push([g_cz1, g_cz2]);
        sum_y += g_y;
        sum_cx += g_cx;
        sum_cz1 += g_cz1;
        sum_cz2 += g_cz2;
    }
    let (norm_y, norm_cx) = (1.0 / sum_y, 1.0 / sum_cx);
    let norm_cz = 1.0 / (sum_cz1 * sum_cz1 + sum_cz2 * sum_cz2).sqrt();
    for w in &mut ycx {
        *w = [w[0] * norm_y, w[1] * norm_cx];
    }
    for w in &mut cz {
        *w = [w[0] * norm_cz, w[1] * norm_cz];
    }
    (ycx, cz)
}

/// Feature filter taps `[g, dg, ddg]`: the Gaussian (sum 1), its first derivative and its
/// second derivative (positive weights sum to 1, negative to −1).
fn feature_filter(ppd: f32) -> Vec<C3> {
    let std_dev = feature_std_dev(ppd);
    let radius = feature_filter_radius(ppd) as i64;
    let mut taps = Vec::new();
    let (mut g_sum, mut dg_neg, mut dg_pos, mut ddg_neg, mut ddg_pos) =
        (0.0f32, 0.0, 0.0, 0.0, 0.0);
    for xx in -radius..=radius {
        let x = xx as f32;
        let g = (-(x * x) / (2.0 * std_dev * std_dev)).exp();
        g_sum += g;
        let dg = -x * g;
        if dg > 0.0 {
            dg_pos += dg;
        } else {
            dg_neg -= dg;
        }
        let ddg = (x * x / (std_dev * std_dev) - 1.0) * g;
        if ddg > 0.0 {
            ddg_pos += ddg;
        } else {
            ddg_neg -= ddg;
        }
        taps.push([g, dg, ddg]);
    }
    // Where every tap but the centre underflows (tiny ppd) a derivative sum is 0: weight 0.
    let div = |v: f32, s: f32| if s > 0.0 { v / s } else { 0.0 };
    for t in &mut taps {
        *t = [
            div(t[0], g_sum),
            div(t[1], if t[1] > 0.0 { dg_pos } else { dg_neg }),
            div(t[2], if t[2] > 0.0 { ddg_pos } else { ddg_neg }),
        ];
    }
    taps
}

// ---------------------------------------------------------------------------------------------
// Separable convolutions with clamp-to-edge borders.

/// Horizontal pass: for each pixel, `K` accumulators of `tap(weight, value)` summed over the
/// taps from −r to r, in that order (as the reference adds them).
fn filter_rows<T: Copy + Sync, W: Sync, const K: usize>(
    src: &[T],
    width: usize,
    weights: &[W],
    tap: impl Fn(&W, &T) -> [f32; K] + Sync,
) -> Vec<[f32; K]> {
    let radius = (weights.len() / 2) as i64;
    let mut out = vec![[0.0f32; K]; src.len()];
    out.par_chunks_mut(width)
        .zip(src.par_chunks(width))
        .for_each(|(row_out, row)| {
            for (x, o) in row_out.iter_mut().enumerate() {
                let mut acc = [0.0f32; K];
                for (i, w) in weights.iter().enumerate() {
                    let xx = (x as i64 + i as i64 - radius).clamp(0, width as i64 - 1) as usize;
                    let v = tap(w, &row[xx]);
                    for k in 0..K {
                        acc[k] += v[k];
                    }
                }
                *o = acc;
            }
        });
    out
}

/// Vertical pass, then `finish` on the `K` sums of each pixel.
fn filter_columns<T: Copy + Sync, W: Sync, const K: usize, O: Send + Default + Clone>(
    src: &[T],
    width: usize,
    height: usize,
    weights: &[W],
    tap: impl Fn(&W, &T) -> [f32; K] + Sync,
    finish: impl Fn([f32; K]) -> O + Sync,
) -> Vec<O> {
    let radius = (weights.len() / 2) as i64;
    let mut out = vec![O::default(); src.len()];
    out.par_chunks_mut(width)
        .enumerate()
        .for_each(|(y, row_out)| {
            for (x, o) in row_out.iter_mut().enumerate() {
                let mut acc = [0.0f32; K];
                for (i, w) in weights.iter().enumerate() {
                    let yy = (y as i64 + i as i64 - radius).clamp(0, height as i64 - 1) as usize;
                    let v = tap(w, &src[yy * width + x]);
                    for k in 0..K {
                        acc[k] += v[k];
                    }
                }
                *o = finish(acc);
            }
        });
    out
}

/// Spatially filtered image in Hunt-adjusted CIELab: YCxCz filtered by the contrast
/// sensitivity functions, back to linear RGB, clamped to [0, 1], to Lab.
fn spatial_hunt_lab(
    ycxcz: &[C3],
    width: usize,
    height: usize,
    ycx: &[[f32; 2]],
    cz: &[[f32; 2]],
) -> Vec<C3> {
    let taps: Vec<[f32; 4]> = ycx
        .iter()
        .zip(cz)
        .map(|(a, b)| [a[0], a[1], b[0], b[1]])
        .collect();
    let rows = filter_rows(ycxcz, width, &taps, |w, c| {
        [w[0] * c[0], w[1] * c[1], w[2] * c[2], w[3] * c[2]]
    });
    filter_columns(
        &rows,
        width,
        height,
        &taps,
        |w, c| [w[0] * c[0], w[1] * c[1], w[2] * c[2], w[3] * c[3]],
        |s| {
            hunt_lab(clamp01(xyz_to_linear_rgb(ycxcz_to_xyz([
                s[0],
                s[1],
                s[2] + s[3],
            ]))))
        },
    )
}

/// Edge and point feature magnitudes of the normalised achromatic channel.
fn features(ycxcz: &[C3], width: usize, height: usize, taps: &[C3]) -> Vec<[f32; 2]> {
    const ONE_OVER_116: f32 = 1.0 / 116.0;
    const SIXTEEN_OVER_116: f32 = 16.0 / 116.0;
    let rows = filter_rows(ycxcz, width, taps, |w, c| {
        let y = c[0] * ONE_OVER_116 + SIXTEEN_OVER_116;
        [w[1] * y, w[2] * y, w[0] * y]
    });
    filter_columns(
        &rows,
        width,
        height,
        taps,
        |w, c| [w[0] * c[0], w[0] * c[1], w[1] * c[2], w[2] * c[2]],
        |[dx, ddx, dy, ddy]| [(dx * dx + dy * dy).sqrt(), (ddx * ddx + ddy * ddy).sqrt()],
    )
}

/// LDR-FLIP of two linear RGB images already in [0, 1] (the reference's `LDR_FLIP`).
fn ldr_core(reference: &[C3], test: &[C3], width: usize, height: usize, ppd: f32) -> Vec<f32> {
    ldr_core_features(reference, test, width, height, ppd, true)
}

/// [`ldr_core`], optionally without the feature (edge and point) term: the colour pipeline
/// alone, for the tests' negative control.
fn ldr_core_features(
    reference: &[C3],
    test: &[C3],
    width: usize,
    height: usize,
    ppd: f32,
    with_features: bool,
) -> Vec<f32> {
    let to_ycxcz = |img: &[C3]| -> Vec<C3> {
        img.par_iter()
            .map(|&c| xyz_to_ycxcz(linear_rgb_to_xyz(c)))
            .collect()
    };
    let (ref_ycc, test_ycc) = (to_ycxcz(reference), to_ycxcz(test));

    let (ycx, cz) = spatial_filters(ppd);
    let ref_lab = spatial_hunt_lab(&ref_ycc, width, height, &ycx, &cz);
    let test_lab = spatial_hunt_lab(&test_ycc, width, height, &ycx, &cz);

    let taps = feature_filter(ppd);
    let ref_feat = features(&ref_ycc, width, height, &taps);
    let test_feat = features(&test_ycc, width, height, &taps);

    let cmax = max_distance();
    let pccmax = GPC * cmax;
    let norm = 1.0 / 2.0f32.sqrt();
    (0..reference.len())
        .into_par_iter()
        .map(|i| {
            let mut color = hyab(ref_lab[i], test_lab[i]).powf(GQC);
            if color < pccmax {
                color *= GPT / pccmax;
            } else {
                color = GPT + ((color - pccmax) / (cmax - pccmax)) * (1.0 - GPT);
            }
            if !with_features {
                return color;
            }
            let edge = (ref_feat[i][0] - test_feat[i][0]).abs();
            let point = (ref_feat[i][1] - test_feat[i][1]).abs();
            let feature = (norm * if edge > point { edge } else { point }).powf(GQF);
            color.powf(1.0 - feature)
        })
        .collect()
}

// ---------------------------------------------------------------------------------------------
// Input checks and entry points.

fn check(reference: &[C3], test: &[C3], width: usize, height: usize, ppd: f32) -> Result<()> {
    let n = width
        .checked_mul(height)
        .ok_or_else(|| Error::Usage(format!("FLIP: image size {width}×{height} overflows")))?;
    if n == 0 {
        return Err(Error::Usage(format!(
            "FLIP: empty image ({width}×{height})"
        )));
    }
    if reference.len() != n || test.len() != n {
        return Err(Error::Usage(format!(
            "FLIP: {width}×{height} needs {n} pixels; the reference has {}, the test {}",
            reference.len(),
            test.len()
        )));
    }
    if !(ppd.is_finite() && ppd > 0.0) {
        return Err(Error::Usage(format!(
            "FLIP: pixels per degree must be positive and finite, not {ppd}"
        )));
    }
    for (name, img) in [("reference", reference), ("test", test)] {
        if let Some(i) = img.iter().position(|c| c.iter().any(|v| !v.is_finite())) {
            return Err(Error::Usage(format!(
                "FLIP: the {name} image has a non-finite value at pixel ({}, {})",
                i % width,
                i / width
            )));
        }
    }
    Ok(())
}

/// LDR-FLIP of two sRGB-encoded images (values in [0, 1], as stored in a PNG; clamped),
/// scan-line order, at `ppd` pixels per degree ([`DEFAULT_PPD`] for the reference's default).
/// Matches `flip_evaluator.evaluate(reference, test, "LDR")`.
pub fn ldr_flip(
    reference: &[C3],
    test: &[C3],
    width: usize,
    height: usize,
    ppd: f32,
) -> Result<FlipMap> {
    ldr_decoded(reference, test, width, height, ppd, |c| {
        clamp01(c.map(srgb_to_linear))
    })
}

/// LDR-FLIP of two linear RGB images with values in [0, 1] (clamped). Matches
/// `flip_evaluator.evaluate(reference, test, "LDR", inputsRGB=False)`.
pub fn ldr_flip_linear(
    reference: &[C3],
    test: &[C3],
    width: usize,
    height: usize,
    ppd: f32,
) -> Result<FlipMap> {
    ldr_decoded(reference, test, width, height, ppd, clamp01)
}

/// LDR-FLIP of the two images after `decode` maps each pixel to linear RGB in [0, 1].
fn ldr_decoded(
    reference: &[C3],
    test: &[C3],
    width: usize,
    height: usize,
    ppd: f32,
    decode: fn(C3) -> C3,
) -> Result<FlipMap> {
    check(reference, test, width, height, ppd)?;
    let lin = |img: &[C3]| -> Vec<C3> { img.iter().map(|&c| decode(c)).collect() };
    let values = ldr_core(&lin(reference), &lin(test), width, height, ppd);
    Ok(FlipMap {
        width,
        height,
        values,
    })
}

// The reference's ACES fit (Narkowicz), with the 0.6 pre-exposure folded in:
// (c²·t0 + c·t1 + t2) / (c²·t3 + c·t4 + t5).
const ACES: [f32; 6] = [
    0.6 * 0.6 * 2.51,
    0.6 * 0.03,
    0.0,
    0.6 * 0.6 * 2.43,
    0.6 * 0.59,
    0.14,
];

/// The ACES fit, in the reference's form where c² is representable; beyond |c| = 1e18, where
/// that form would square c to ∞ and give ∞/∞, numerator and denominator divided by c² (there
/// both forms equal t0/t3 to f32 precision, the 1/c terms being below 1e-18, and the divided
/// one is exactly t0/t3 at c = ±∞). Neither denominator has a real root.
fn aces(c: f32) -> f32 {
    let t = &ACES;
    if c.abs() > 1e18 {
        let r = 1.0 / c;
        (t[0] + r * (t[1] + r * t[2])) / (t[3] + r * (t[4] + r * t[5]))
    } else {
        ((c * c) * t[0] + c * t[1] + t[2]) / (c * c * t[3] + c * t[4] + t[5])
    }
}

/// Largest exposure, in stops, whose 2^exposure is a finite f32.
const MAX_EXPOSURE: f32 = 127.0;

/// HDR-FLIP's automatic exposures from the reference (linear RGB): the start exposure maps
/// the largest luminance, the stop exposure the median luminance, to where the tone mapper
/// reaches 0.85; `count = max(2, ceil(stop − start))`.
pub fn hdr_exposures(reference: &[C3]) -> Exposures {
    // Solve aces(x) = 0.85 for its larger root.
    let t = 0.85f32;
    let a = ACES[0] - t * ACES[3];
    let b = ACES[1] - t * ACES[4];
    let c = ACES[2] - t * ACES[5];
    let x_max = if a == 0.0 {
        -c / b
    } else {
        let d1 = -0.5 * (b / a);
        let d2 = ((d1 * d1) - (c / a)).sqrt();
        d1 + d2
    };

    let mut lum: Vec<f32> = reference.iter().map(|&p| luminance(p)).collect();
    let y_max = lum.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let mid = lum.len() / 2;
    let y_median = if lum.is_empty() {
        0.0
    } else {
        *lum.select_nth_unstable_by(mid, f32::total_cmp).1
    };
    // flip-evaluator 1.7 floors the median at f32::EPSILON (more than half the pixels black);
    // the maximum too here (the reference exits on an all-black reference: start > stop).
    let y_median = y_median.max(f32::EPSILON);
    let y_max = y_max.max(f32::EPSILON);
    let stops = |y: f32| {
        let e = (x_max / y).log2();
        if e.is_finite() {
            e
        } else {
            // A luminance above ~1e38 (ratio 0): f64, within ±256.
            ((x_max as f64).log2() - (y as f64).log2()).clamp(-256.0, 256.0) as f32
        }
    };
    let (start, stop) = (stops(y_max), stops(y_median));
    let count = 2.0f32.max((stop - start).ceil()) as u32;
    Exposures { start, stop, count }
}

/// HDR-FLIP of two linear RGB radiance images (non-negative, any range; scan-line order) at
/// `ppd` pixels per degree, with exposures from [`hdr_exposures`] of the reference.
/// Matches `flip_evaluator.evaluate(reference, test, "HDR")`.
pub fn hdr_flip(
    reference: &[C3],
    test: &[C3],
    width: usize,
    height: usize,
    ppd: f32,
) -> Result<FlipMap> {
    Ok(hdr_flip_with(reference, test, width, height, ppd, None)?.map)
}

/// [`hdr_flip`] with explicit exposures (`None`: [`hdr_exposures`] of the reference), also
/// returning the exposures used.
pub fn hdr_flip_with(
    reference: &[C3],
    test: &[C3],
    width: usize,
    height: usize,
    ppd: f32,
    exposures: Option<Exposures>,
) -> Result<HdrFlip> {
    check(reference, test, width, height, ppd)?;
    let exposures = match exposures {
        Some(e) => {
            if !(e.start <= e.stop && e.stop <= MAX_EXPOSURE && e.start.is_finite() && e.count >= 2)
            {
                return Err(Error::Usage(format!(
                    "FLIP: exposures need a finite start ≤ stop ≤ {MAX_EXPOSURE} (2^stop a finite \
                     f32) and a count of 2 or more, not {e:?}"
                )));
            }
            e
        }
        None => hdr_exposures(reference),
    };
    let step = (exposures.stop - exposures.start) / (exposures.count - 1) as f32;
    let mut values = vec![0.0f32; width * height];
    for i in 0..exposures.count {
        let exposure = exposures.start + i as f32 * step;
        let m = 2.0f32.powf(exposure);
        let tone_map = |img: &[C3]| -> Vec<C3> {
            img.par_iter()
                .map(|c| {
                    c.map(|v| {
                        // m is finite and positive, v finite: v·m is never NaN (at most ±∞,
                        // which `aces` takes).
                        aces(v * m).clamp(0.0, 1.0)
                    })
                })
                .collect()
        };
        let ldr = ldr_core(&tone_map(reference), &tone_map(test), width, height, ppd);
        for (v, l) in values.iter_mut().zip(ldr) {
            if l > *v {
                *v = l;
            }
        }
    }
    Ok(HdrFlip {
        map: FlipMap {
            width,
            height,
            values,
        },
        exposures,
    })
}

fn image_f32(img: &Image) -> Vec<C3> {
    img.pixels
        .iter()
        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32])
        .collect()
}

/// HDR-FLIP of two of the crate's images (linear radiance) at [`DEFAULT_PPD`].
pub fn hdr_flip_image(reference: &Image, test: &Image) -> Result<FlipMap> {
    hdr_flip_image_ppd(reference, test, DEFAULT_PPD)
}

/// HDR-FLIP of two of the crate's images at `ppd` pixels per degree.
pub fn hdr_flip_image_ppd(reference: &Image, test: &Image, ppd: f32) -> Result<FlipMap> {
    if (reference.width, reference.height) != (test.width, test.height) {
        return Err(Error::Usage(format!(
            "FLIP: the reference is {}×{}, the test {}×{}",
            reference.width, reference.height, test.width, test.height
        )));
    }
    hdr_flip(
        &image_f32(reference),
        &image_f32(test),
        reference.width as usize,
        reference.height as usize,
        ppd,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 16×16 pair of `scripts/flip-check.py`'s `tiny_pair` (exact f32 arithmetic, so the
    /// script and this test build the same bits).
    fn tiny_pair() -> (Vec<C3>, Vec<C3>) {
        let px = |x: u32, y: u32, extra: u32| -> C3 {
            [0, 1, 2].map(|c| ((x * 3 + y * 5 + c * 7 + extra) % 16) as f32 / 15.0)
        };
        let mut r = Vec::new();
        let mut t = Vec::new();
        for y in 0..16 {
            for x in 0..16 {
                r.push(px(x, y, 0));
                t.push(px(x, y, (x * y) % 3));
            }
        }
        (r, t)
    }

    /// `tiny_hdr`: ×4 with an "emitter" of 12 at rows 2..4, columns 5..8.
    fn tiny_hdr(img: &[C3]) -> Vec<C3> {
        img.iter()
            .enumerate()
            .map(|(i, c)| {
                let (x, y) = (i % 16, i / 16);
                if (2..4).contains(&y) && (5..8).contains(&x) {
                    [12.0; 3]
                } else {
                    c.map(|v| v * 4.0)
                }
            })
            .collect()
    }

    /// Values from flip-evaluator 1.7 (`python scripts/flip-check.py --constants`): the f64
    /// mean of its map, and pixels (0, 0), (5, 3), (15, 15), (7, 12).
    struct Expected {
        mean: f64,
        pixels: [f64; 4],
    }
    const LDR_DEFAULT: Expected = Expected {
        mean: 0.22499197933939286,
        pixels: [
            0.2843470275402069,
            0.16764089465141296,
            0.10298571735620499,
            0.1989019215106964,
        ],
    };
    const LDR_PPD30: Expected = Expected {
        mean: 0.31803919118101476,
        pixels: [
            0.21879450976848602,
            0.13883763551712036,
            0.09239158034324646,
            0.1109728142619133,
        ],
    };
    const HDR_DEFAULT: Expected = Expected {
        mean: 0.1833350516972132,
        pixels: [
            0.19929908215999603,
            0.13841113448143005,
            0.06772912293672562,
            0.2653237283229828,
        ],
    };
    const HDR_PPD30: Expected = Expected {
        mean: 0.2820766894801636,
        pixels: [
            0.14728672802448273,
            0.1499958634376526,
            0.02740039862692356,
            0.1847328245639801,
        ],
    };
    /// The reference's exposures for the HDR tiny pair (any ppd), as Python printed them.
    #[allow(clippy::excessive_precision)]
    const HDR_EXPOSURES: (f32, f32, u32) = (-2.5016653537750244, 0.09900197386741638, 3);

    /// Agreement bar: measured agreement is ~1e-7 (float rounding; docs/flip.md); 1e-5 leaves
    /// room for another libm's powf/expf and still fails every negative control below.
    const PIXEL_TOL: f64 = 1e-5;
    const MEAN_REL_TOL: f64 = 1e-5;

    fn agrees(map: &FlipMap, e: &Expected) -> bool {
        let at = [(0, 0), (5, 3), (15, 15), (7, 12)];
        let pixels_ok = at
            .iter()
            .zip(e.pixels)
            .all(|(&(x, y), v)| (map.get(x, y) as f64 - v).abs() <= PIXEL_TOL);
        pixels_ok && ((map.mean() - e.mean) / e.mean).abs() <= MEAN_REL_TOL
    }

    fn describe(map: &FlipMap) -> String {
        format!(
            "mean {} pixels {:?}",
            map.mean(),
            [(0, 0), (5, 3), (15, 15), (7, 12)].map(|(x, y)| map.get(x, y))
        )
    }

    #[test]
    fn matches_reference_implementation_on_the_tiny_pair() {
        let (r, t) = tiny_pair();
        let (hr, ht) = (tiny_hdr(&r), tiny_hdr(&t));
        for (map, e) in [
            (ldr_flip(&r, &t, 16, 16, DEFAULT_PPD).unwrap(), &LDR_DEFAULT),
            (ldr_flip(&r, &t, 16, 16, 30.0).unwrap(), &LDR_PPD30),
            (
                hdr_flip(&hr, &ht, 16, 16, DEFAULT_PPD).unwrap(),
                &HDR_DEFAULT,
            ),
            (hdr_flip(&hr, &ht, 16, 16, 30.0).unwrap(), &HDR_PPD30),
        ] {
            assert!(agrees(&map, e), "{}", describe(&map));
        }
        let ex = hdr_exposures(&hr);
        assert!((ex.start - HDR_EXPOSURES.0).abs() < 1e-6, "{ex:?}");
        assert!((ex.stop - HDR_EXPOSURES.1).abs() < 1e-6, "{ex:?}");
        assert_eq!(ex.count, HDR_EXPOSURES.2);
    }

    /// Negative controls: the committed-constant check above fails when one part of the
    /// pipeline is wrong, so it does test something.
    #[test]
    fn the_constant_check_fails_with_a_wrong_pipeline() {
        let (r, t) = tiny_pair();
        let (hr, ht) = (tiny_hdr(&r), tiny_hdr(&t));
        let lin = |img: &[C3]| -> Vec<C3> { img.iter().map(|c| c.map(srgb_to_linear)).collect() };
        let wrong: [(&str, FlipMap, &Expected); 6] = [
            // 60 instead of 67.02 pixels per degree (same filter radii, 10 and 9).
            (
                "ppd 60",
                ldr_flip(&r, &t, 16, 16, 60.0).unwrap(),
                &LDR_DEFAULT,
            ),
            // A round 67 instead of the reference's 67.0206: mean off by 2.6e-4 relative.
            (
                "ppd 67",
                ldr_flip(&r, &t, 16, 16, 67.0).unwrap(),
                &LDR_DEFAULT,
            ),
            // The sRGB inputs taken as linear (sRGB decode skipped).
            (
                "no sRGB decode",
                ldr_flip_linear(&r, &t, 16, 16, DEFAULT_PPD).unwrap(),
                &LDR_DEFAULT,
            ),
            // The feature (edge/point) pipeline skipped.
            (
                "no features",
                FlipMap {
                    width: 16,
                    height: 16,
                    values: ldr_core_features(&lin(&r), &lin(&t), 16, 16, DEFAULT_PPD, false),
                },
                &LDR_DEFAULT,
            ),
            // HDR with only the two end exposures.
            (
                "2 exposures",
                hdr_flip_with(
                    &hr,
                    &ht,
                    16,
                    16,
                    DEFAULT_PPD,
                    Some(Exposures {
                        start: HDR_EXPOSURES.0,
                        stop: HDR_EXPOSURES.1,
                        count: 2,
                    }),
                )
                .unwrap()
                .map,
                &HDR_DEFAULT,
            ),
            // HDR-FLIP at exposure 0 only, i.e. LDR-FLIP of the tone-mapped images.
            (
                "exposure 0",
                hdr_flip_with(
                    &hr,
                    &ht,
                    16,
                    16,
                    DEFAULT_PPD,
                    Some(Exposures {
                        start: 0.0,
                        stop: 0.0,
                        count: 2,
                    }),
                )
                .unwrap()
                .map,
                &HDR_DEFAULT,
            ),
        ];
        for (name, map, e) in &wrong {
            assert!(
                !agrees(map, e),
                "{name} passes the check: {}",
                describe(map)
            );
        }
    }

    #[test]
    fn identical_images_give_zero() {
        let (r, _) = tiny_pair();
        let h = tiny_hdr(&r);
        for map in [
            ldr_flip(&r, &r, 16, 16, DEFAULT_PPD).unwrap(),
            ldr_flip_linear(&r, &r, 16, 16, DEFAULT_PPD).unwrap(),
            hdr_flip(&h, &h, 16, 16, DEFAULT_PPD).unwrap(),
        ] {
            assert!(map.values.iter().all(|&v| v == 0.0), "{}", describe(&map));
            assert_eq!(map.mean(), 0.0);
        }
    }

    /// LDR-FLIP is symmetric bit for bit; HDR-FLIP is once its exposures are fixed (only the
    /// automatic exposures depend on which image is the reference).
    #[test]
    fn symmetry_where_it_holds() {
        let (r, t) = tiny_pair();
        assert_eq!(
            ldr_flip(&r, &t, 16, 16, DEFAULT_PPD).unwrap(),
            ldr_flip(&t, &r, 16, 16, DEFAULT_PPD).unwrap()
        );
        let (hr, ht) = (tiny_hdr(&r), tiny_hdr(&t));
        let ex = Some(hdr_exposures(&hr));
        assert_eq!(
            hdr_flip_with(&hr, &ht, 16, 16, DEFAULT_PPD, ex)
                .unwrap()
                .map,
            hdr_flip_with(&ht, &hr, 16, 16, DEFAULT_PPD, ex)
                .unwrap()
                .map
        );
    }

    #[test]
    fn filter_radii_and_default_viewing_condition() {
        assert!((DEFAULT_PPD - 67.020_645).abs() < 1e-4, "{DEFAULT_PPD}");
        assert_eq!(spatial_filter_radius(DEFAULT_PPD), 10);
        assert_eq!(feature_filter_radius(DEFAULT_PPD), 9);
        assert_eq!(spatial_filter_radius(30.0), 5);
        assert_eq!(feature_filter_radius(30.0), 4);
        // Feature filter: Gaussian sums to 1, derivative halves to ±1.
        let taps = feature_filter(DEFAULT_PPD);
        let sum = |k: usize, pos: bool| -> f32 {
            taps.iter()
                .map(|t| t[k])
                .filter(|&v| (v > 0.0) == pos)
                .sum()
        };
        assert!((sum(0, true) - 1.0).abs() < 1e-6);
        for k in [1, 2] {
            assert!((sum(k, true) - 1.0).abs() < 1e-6 && (sum(k, false) + 1.0).abs() < 1e-6);
        }
    }

    fn finite_in_unit(map: &FlipMap) -> bool {
        map.values.iter().all(|v| (0.0..=1.0).contains(v)) && map.mean().is_finite()
    }

    #[test]
    fn no_nan_on_zero_constant_and_very_bright_images() {
        let (w, h) = (24, 17);
        let n = w * h;
        let zero = vec![[0.0f32; 3]; n];
        let half = vec![[0.5f32; 3]; n];
        let bright = vec![[1e4f32; 3]; n];
        let mut spots = half.clone();
        for i in (0..n).step_by(7) {
            spots[i] = [1e4, 2e4, 5e3];
        }
        let huge = vec![[3e38f32; 3]; n];
        let tiny = vec![[1e-40f32; 3]; n];
        let images = [&zero, &half, &bright, &spots, &huge, &tiny];
        for a in images {
            for b in images {
                for ppd in [DEFAULT_PPD, 1.0, 0.01, 500.0] {
                    let l = ldr_flip(a, b, w, h, ppd).unwrap();
                    let hd = hdr_flip_with(a, b, w, h, ppd, None).unwrap();
                    assert!(finite_in_unit(&l) && finite_in_unit(&hd.map), "ppd {ppd}");
                    assert!(hd.exposures.start.is_finite() && hd.exposures.stop.is_finite());
                }
            }
        }
        // Degenerate shapes: one pixel, one row, one column.
        for (w, h) in [(1, 1), (9, 1), (1, 9)] {
            let a = vec![[0.2f32, 0.9, 3.0]; w * h];
            let map = hdr_flip(&a, &zero[..w * h], w, h, DEFAULT_PPD).unwrap();
            assert!(finite_in_unit(&map));
        }
    }

    /// The ACES fit is finite for every input, ±∞ included, and continuous where it switches
    /// form; the reference's form alone gives ∞/∞ = NaN there (the negative control).
    #[test]
    fn aces_is_finite_everywhere_and_continuous_at_its_switch() {
        let limit = ACES[0] / ACES[3];
        for c in [f32::INFINITY, f32::NEG_INFINITY, f32::MAX, -f32::MAX, 1e30] {
            assert!(
                (aces(c) - limit).abs() <= limit * f32::EPSILON,
                "{c}: {}",
                aces(c)
            );
        }
        let (below, above) = (aces(1e18), aces(1e18f32.next_up()));
        assert!(
            (below - above).abs() <= limit * f32::EPSILON,
            "{below} {above}"
        );
        let t = &ACES;
        let direct = |c: f32| ((c * c) * t[0] + c * t[1] + t[2]) / (c * c * t[3] + c * t[4] + t[5]);
        assert!(direct(1e30).is_nan());
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let a = vec![[0.5f32; 3]; 12];
        assert!(ldr_flip(&a, &a[..11], 4, 3, DEFAULT_PPD).is_err());
        assert!(hdr_flip(&a, &a, 4, 4, DEFAULT_PPD).is_err());
        assert!(hdr_flip(&[], &[], 0, 0, DEFAULT_PPD).is_err());
        assert!(hdr_flip(&a, &a, usize::MAX, 2, DEFAULT_PPD).is_err());
        for ppd in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert!(ldr_flip(&a, &a, 4, 3, ppd).is_err());
        }
        let mut b = a.clone();
        b[5][1] = f32::NAN;
        assert!(hdr_flip(&a, &b, 4, 3, DEFAULT_PPD).is_err());
        b[5][1] = f32::INFINITY;
        assert!(ldr_flip(&b, &a, 4, 3, DEFAULT_PPD).is_err());
        let bad = Exposures {
            start: 1.0,
            stop: 0.0,
            count: 2,
        };
        assert!(hdr_flip_with(&a, &a, 4, 3, DEFAULT_PPD, Some(bad)).is_err());
        // 2^200 is no finite f32; 2^127 is.
        let over = Exposures {
            start: 0.0,
            stop: 200.0,
            count: 2,
        };
        assert!(hdr_flip_with(&a, &a, 4, 3, DEFAULT_PPD, Some(over)).is_err());
        let top = Exposures {
            stop: MAX_EXPOSURE,
            ..over
        };
        let hd = hdr_flip_with(&a, &a, 4, 3, DEFAULT_PPD, Some(top)).unwrap();
        assert!(finite_in_unit(&hd.map));
        let img = |w: u32, h: u32| Image {
            width: w,
            height: h,
            pixels: vec![[1.0; 3]; (w * h) as usize],
        };
        assert!(hdr_flip_image(&img(4, 3), &img(3, 4)).is_err());
        assert!(hdr_flip_image(&img(4, 3), &img(4, 3)).unwrap().mean() == 0.0);
        let mut f64_overflow = img(4, 3);
        f64_overflow.pixels[0][0] = 1e300; // not representable in f32
        assert!(hdr_flip_image(&f64_overflow, &img(4, 3)).is_err());
    }
}
