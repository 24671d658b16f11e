//! Image error metrics against a reference, accumulated in f64.

use crate::film::Image;

/// Root-mean-square error over all pixels and channels.
pub fn rmse(img: &Image, reference: &Image) -> f64 {
    let n = (img.pixels.len() * 3) as f64;
    let se: f64 = img
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>())
        .sum();
    (se / n).sqrt()
}

/// The ε of relMSE's denominator r² + ε.
pub const EPS: f64 = 0.01;

/// Relative MSE, mean over pixels and channels of (x - r)² / (r² + ε) with ε = 0.01
/// (Rousselle et al. 2011): the ε is part of the metric's definition, so dark pixels do not
/// dominate.
pub fn relmse(img: &Image, reference: &Image) -> f64 {
    let n = (img.pixels.len() * 3) as f64;
    let s: f64 = img
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| {
            (0..3)
                .map(|c| (a[c] - b[c]).powi(2) / (b[c] * b[c] + EPS))
                .sum::<f64>()
        })
        .sum();
    s / n
}

/// The relMSE a reference's own noise adds in expectation: mean over pixels and channels of
/// Var(r) / (r² + ε), with `variance` the per-pixel variance of the reference mean. For an
/// image x independent of the reference r (their random streams never coincide),
/// E[(x − r)²] = E[(x − μ)²] + Var(r), so relMSE − this is the relMSE against the truth, up to
/// evaluating the weight 1/(r² + ε) at r instead of μ (a relative error of order
/// Var(r)/(r² + ε), small where the reference is good enough to compare against).
pub fn relmse_floor(variance: &Image, reference: &Image) -> f64 {
    let n = (reference.pixels.len() * 3) as f64;
    let s: f64 = variance
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(v, b)| (0..3).map(|c| v[c] / (b[c] * b[c] + EPS)).sum::<f64>())
        .sum();
    s / n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        let r = Image {
            width: 2,
            height: 1,
            pixels: vec![[1.0; 3], [0.0; 3]],
        };
        let a = Image {
            width: 2,
            height: 1,
            pixels: vec![[1.0; 3], [2.0; 3]],
        };
        assert!((rmse(&a, &r) - 2.0f64.sqrt()).abs() < 1e-12);
        assert!((relmse(&a, &r) - 0.5 * 4.0 / 0.01).abs() < 1e-9);
        assert_eq!(rmse(&r, &r), 0.0);
    }

    /// relMSE with reference values other than 0 and 1 (where r and r² coincide): each term is
    /// (x − r)²/(r² + 0.01), averaged over pixels and channels.
    #[test]
    fn relmse_divides_by_the_squared_reference() {
        let r = Image {
            width: 1,
            height: 2,
            pixels: vec![[2.0, 0.5, 3.0], [0.25, 4.0, 1.5]],
        };
        let x = Image {
            width: 1,
            height: 2,
            pixels: vec![[3.0, 0.0, 3.0], [0.75, 2.0, 1.0]],
        };
        let terms = [
            1.0 / 4.01,
            0.25 / 0.26,
            0.0,
            0.25 / (0.0625 + 0.01),
            4.0 / 16.01,
            0.25 / 2.26,
        ];
        let expected = terms.iter().sum::<f64>() / 6.0;
        assert!((relmse(&x, &r) - expected).abs() < 1e-12 * expected);
        let se: f64 = [1.0, 0.25, 0.0, 0.25, 4.0, 0.25].iter().sum();
        assert!((rmse(&x, &r) - (se / 6.0).sqrt()).abs() < 1e-12);
    }
}
