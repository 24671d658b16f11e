//! Every sampler dibench has, registered once for the χ² suite and `dibench warp`: a name,
//! its parameters with defaults, the parameter sets the test suite runs (extremes included),
//! and a constructor that builds the [`WarpCase`] from parameters.

use super::{Chart, DEFAULT_SLACK, WarpCase};
use crate::bsdf::Bsdf;
use crate::geometry::Ray;
use crate::geometry::sphere::Sphere;
use crate::geometry::triangle::{Triangle, WatertightRay};
use crate::lights::mesh::MeshLight;
use crate::lights::quad::QuadLight;
use crate::lights::sphere::SphereLight;
use crate::lights::{Light, LightMethods, MeshMethod, QuadMethod, SphereMethod};
use crate::sampling::warp::*;
use glam::Vec3;
use std::collections::BTreeMap;
use std::f32::consts::PI;

pub type Params = BTreeMap<String, f64>;

pub struct WarpEntry {
    pub name: &'static str,
    pub describe: &'static str,
    /// Parameters and their defaults.
    pub params: &'static [(&'static str, f64)],
    /// Overrides the test suite runs, one parameter set each (empty: the defaults).
    pub suite: &'static [&'static [(&'static str, f64)]],
    /// The lecture's inconsistent pair: kept so the harness can show that it fails.
    pub expect_fail: bool,
    pub build: fn(&Params) -> Result<WarpCase, String>,
}

impl WarpEntry {
    /// Defaults overridden by `overrides`; unknown names are errors.
    pub fn params(&self, overrides: &[(String, f64)]) -> Result<Params, String> {
        let mut p: Params = self
            .params
            .iter()
            .map(|(k, v)| (k.to_string(), *v))
            .collect();
        for (k, v) in overrides {
            if !p.contains_key(k) {
                let known: Vec<_> = self.params.iter().map(|(k, _)| *k).collect();
                return Err(format!(
                    "sampler `{}` has no parameter `{k}` (parameters: {})",
                    self.name,
                    known.join(", ")
                ));
            }
            if !v.is_finite() {
                return Err(format!("parameter `{k}` must be finite, got {v}"));
            }
            p.insert(k.clone(), *v);
        }
        Ok(p)
    }

    /// The parameter sets of the test suite.
    pub fn suite_params(&self) -> Vec<Params> {
        let sets: Vec<&[(&str, f64)]> = if self.suite.is_empty() {
            vec![&[]]
        } else {
            self.suite.to_vec()
        };
        sets.into_iter()
            .map(|s| {
                self.params(
                    &s.iter()
                        .map(|(k, v)| (k.to_string(), *v))
                        .collect::<Vec<_>>(),
                )
                .expect("suite parameters are valid")
            })
            .collect()
    }
}

fn label(name: &str, p: &Params) -> String {
    let args: Vec<String> = p.iter().map(|(k, v)| format!("{k}={v}")).collect();
    format!("{name}({})", args.join(", "))
}

fn get(p: &Params, k: &str) -> f32 {
    p[k] as f32
}

/// 1 - cos θ about +z from a unit direction, exact near the pole.
fn omc_z(w: Vec3) -> f32 {
    if w.z > 0.0 {
        (w.x * w.x + w.y * w.y) / (1.0 + w.z)
    } else {
        1.0 - w.z
    }
}

pub fn registry() -> Vec<WarpEntry> {
    let mut v = vec![
        WarpEntry {
            name: "uniform-hemisphere",
            describe: "uniform hemisphere about +z, pdf 1/2π",
            params: &[],
            suite: &[],
            expect_fail: false,
            build: |p| {
                Ok(WarpCase {
                    label: label("uniform-hemisphere", p),
                    sample: Box::new(|u| {
                        Some((
                            sample_uniform_hemisphere([u[0], u[1]]),
                            UNIFORM_HEMISPHERE_PDF,
                        ))
                    }),
                    pdf: Box::new(|w| {
                        if w.z > 0.0 {
                            UNIFORM_HEMISPHERE_PDF as f64
                        } else {
                            0.0
                        }
                    }),
                    mismatch_slack: DEFAULT_SLACK,
                    chart: Chart::cap(Vec3::Z, 1.0 + 1e-6),
                })
            },
        },
        WarpEntry {
            name: "cosine-hemisphere",
            describe: "cosine-weighted hemisphere (Malley, concentric disk), pdf cos θ/π",
            params: &[],
            suite: &[],
            expect_fail: false,
            build: |p| {
                Ok(WarpCase {
                    label: label("cosine-hemisphere", p),
                    sample: Box::new(|u| {
                        let w = sample_cosine_hemisphere([u[0], u[1]]);
                        (w.z > 0.0).then(|| (w, cosine_hemisphere_pdf(w.z)))
                    }),
                    pdf: Box::new(|w| cosine_hemisphere_pdf(w.z) as f64),
                    mismatch_slack: DEFAULT_SLACK,
                    chart: Chart::cap(Vec3::Z, 1.0 + 1e-6),
                })
            },
        },
        WarpEntry {
            name: "uniform-sphere",
            describe: "uniform sphere, pdf 1/4π",
            params: &[],
            suite: &[],
            expect_fail: false,
            build: |p| {
                Ok(WarpCase {
                    label: label("uniform-sphere", p),
                    sample: Box::new(|u| {
                        Some((sample_uniform_sphere([u[0], u[1]]), UNIFORM_SPHERE_PDF))
                    }),
                    pdf: Box::new(|_| UNIFORM_SPHERE_PDF as f64),
                    mismatch_slack: DEFAULT_SLACK,
                    chart: Chart::sphere(),
                })
            },
        },
        WarpEntry {
            name: "uniform-cone",
            describe: "uniform cone about +z with half-angle sin θmax = s, stable 1 - cos θmax",
            params: &[("s", 0.5)],
            suite: &[
                &[("s", 0.5)],
                &[("s", 0.999)],
                &[("s", 1e-2)],
                &[("s", 1e-3)],
            ],
            expect_fail: false,
            build: |p| {
                let s = get(p, "s");
                if !(s > 0.0 && s <= 1.0) {
                    return Err("s must be in (0, 1]".into());
                }
                let omc = one_minus_cos_from_sin2(s * s);
                Ok(WarpCase {
                    label: label("uniform-cone", p),
                    sample: Box::new(move |u| {
                        Some((
                            sample_uniform_cone([u[0], u[1]], omc),
                            uniform_cone_pdf(omc),
                        ))
                    }),
                    pdf: Box::new(move |w| {
                        if omc_z(w) <= omc {
                            uniform_cone_pdf(omc) as f64
                        } else {
                            0.0
                        }
                    }),
                    mismatch_slack: DEFAULT_SLACK,
                    chart: Chart::cap(Vec3::Z, omc as f64 * 1.01),
                })
            },
        },
        WarpEntry {
            name: "phong-lobe",
            describe: "Phong lobe about +z, pdf (n+1)/2π cos^n α, cos α = u^(1/(n+1)) via expm1",
            params: &[("n", 20.0)],
            suite: &[
                &[("n", 0.0)],
                &[("n", 1.0)],
                &[("n", 20.0)],
                &[("n", 1e3)],
                &[("n", 1e4)],
                &[("n", 1e5)],
            ],
            expect_fail: false,
            build: |p| {
                let n = get(p, "n");
                if n < 0.0 {
                    return Err("n must be ≥ 0".into());
                }
                Ok(WarpCase {
                    label: label("phong-lobe", p),
                    sample: Box::new(move |u| {
                        let w = sample_phong_lobe([u[0], u[1]], n);
                        Some((w, phong_lobe_pdf(omc_z(w), n)))
                    }),
                    pdf: Box::new(move |w| phong_lobe_pdf(omc_z(w), n) as f64),
                    // The lobe holds all but e^-40 of its mass within 1 - cos α ≤ 40/(n+1).
                    mismatch_slack: DEFAULT_SLACK,
                    chart: Chart::cap(Vec3::Z, (40.0 / (n as f64 + 1.0)).min(1.0 + 1e-6)),
                })
            },
        },
        WarpEntry {
            name: "phong-lecture",
            describe: "the lecture's pair: cos α = u^(1/(n+2)) with pdf (n+2)/2π cos^n α — inconsistent, fails",
            params: &[("n", 20.0)],
            suite: &[&[("n", 1.0)], &[("n", 20.0)]],
            expect_fail: true,
            build: |p| {
                let n = get(p, "n");
                let pdf = move |w: Vec3| {
                    if w.z > 0.0 {
                        (n + 2.0) / (2.0 * PI) * w.z.powf(n)
                    } else {
                        0.0
                    }
                };
                Ok(WarpCase {
                    label: label("phong-lecture", p),
                    sample: Box::new(move |u| {
                        let cos = (1.0 - u[0]).powf(1.0 / (n + 2.0));
                        let sin = (1.0 - cos * cos).max(0.0).sqrt();
                        let phi = 2.0 * PI * u[1];
                        let w = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
                        Some((w, pdf(w)))
                    }),
                    pdf: Box::new(move |w| pdf(w) as f64),
                    mismatch_slack: DEFAULT_SLACK,
                    chart: Chart::cap(Vec3::Z, 1.0 + 1e-6),
                })
            },
        },
        WarpEntry {
            name: "bsdf-blend",
            describe: "diffuse + normalized Phong blend, lobe chosen by coefficient; wo at theta_o from the normal",
            params: &[("kd", 0.5), ("ks", 0.4), ("n", 10.0), ("theta_o", 30.0)],
            suite: &[
                &[],
                &[("kd", 0.0), ("ks", 1.0), ("n", 5.0), ("theta_o", 70.0)],
                &[("kd", 0.9), ("ks", 0.1), ("n", 50.0), ("theta_o", 0.0)],
            ],
            expect_fail: false,
            build: |p| {
                let (kd, ks, n, theta) = (
                    get(p, "kd"),
                    get(p, "ks"),
                    get(p, "n"),
                    get(p, "theta_o").to_radians(),
                );
                if kd < 0.0 || ks < 0.0 || kd + ks > 1.0 || kd + ks == 0.0 || n < 0.0 {
                    return Err("need kd, ks ≥ 0 with 0 < kd + ks ≤ 1, and n ≥ 0".into());
                }
                let bsdf = Bsdf::new(Vec3::splat(kd), Vec3::splat(ks), n);
                let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
                Ok(WarpCase {
                    label: label("bsdf-blend", p),
                    sample: Box::new(move |u| {
                        let s = bsdf.sample(Vec3::Z, wo, u);
                        Some((s.wi, s.pdf))
                    }),
                    pdf: Box::new(move |w| bsdf.pdf(Vec3::Z, wo, w) as f64),
                    mismatch_slack: DEFAULT_SLACK,
                    chart: Chart::sphere(),
                })
            },
        },
        quad_entry(
            "quad-area",
            "quad light, uniform by area, converted to solid angle",
            QuadMethod::Area,
        ),
        quad_entry(
            "quad-solid-angle",
            "quad light, spherical rectangle (Ureña et al. 2013)",
            QuadMethod::SolidAngle,
        ),
        sphere_entry(
            "sphere-area",
            "sphere light, uniform by area over the whole sphere",
            SphereMethod::Area,
        ),
        sphere_entry(
            "sphere-cap",
            "sphere light, uniform by area over the visible cap",
            SphereMethod::Cap,
        ),
        sphere_entry(
            "sphere-cone",
            "sphere light, uniform in the subtended cone",
            SphereMethod::Cone,
        ),
        mesh_entry(
            "mesh-area",
            "mesh light, triangle by area then uniform by area",
            MeshMethod::Area,
        ),
        mesh_entry(
            "mesh-solid-angle",
            "mesh light, triangle by area then spherical triangle (Arvo 1995)",
            MeshMethod::SolidAngle,
        ),
    ];
    v.extend(env_entries());
    v
}

pub fn by_name(name: &str) -> Option<WarpEntry> {
    registry().into_iter().find(|e| e.name == name)
}

/// A light seen from the origin: sample by `methods`, pdf by finding where a direction meets
/// the light (`hit`) and asking the light's pdf routine. The chart hugs `support`.
fn light_case(
    label: String,
    light: Light,
    methods: LightMethods,
    hit: impl Fn(Vec3) -> Option<(Vec3, u32)> + 'static,
    chart: Chart,
) -> WarpCase {
    let l2 = light.clone();
    WarpCase {
        label,
        sample: Box::new(move |u| light.sample(Vec3::ZERO, u, &methods).map(|s| (s.wi, s.pdf))),
        pdf: Box::new(move |w| match hit(w) {
            Some((q, local)) => l2.pdf(Vec3::ZERO, q, local, &methods) as f64,
            None => 0.0,
        }),
        mismatch_slack: DEFAULT_SLACK,
        chart,
    }
}

/// The smallest cap about the direction to `center` containing every point (a convex shape's
/// solid angle is bounded by its vertices), with a margin for rounding.
fn cap_around(center: Vec3, points: &[Vec3]) -> Chart {
    let axis = center.normalize();
    let h = points
        .iter()
        .map(|p| omc_between(axis, p.normalize()))
        .fold(0.0f64, f64::max);
    Chart::cap(axis, (h * 1.02).max(1e-9))
}

fn omc_between(a: Vec3, b: Vec3) -> f64 {
    0.5 * (a.as_dvec3() - b.as_dvec3()).length_squared()
}

fn quad_entry(name: &'static str, describe: &'static str, method: QuadMethod) -> WarpEntry {
    WarpEntry {
        name,
        describe,
        params: &[("dist", 2.0), ("tilt", 30.0), ("size", 1.0)],
        suite: &[
            &[],
            &[("tilt", 0.0), ("size", 4.0), ("dist", 1.0)],
            &[("tilt", 85.0)],
            &[("size", 0.01), ("dist", 5.0)],
        ],
        expect_fail: false,
        build: match method {
            QuadMethod::Area => |p| build_quad(p, "quad-area", QuadMethod::Area),
            QuadMethod::SolidAngle => |p| build_quad(p, "quad-solid-angle", QuadMethod::SolidAngle),
        },
    }
}

/// A square of side `size` centred `dist` above the origin on +z, its emitting normal tilted by
/// `tilt` degrees away from facing the origin (89.5: almost edge-on, a grazing quad).
fn build_quad(p: &Params, name: &str, method: QuadMethod) -> Result<WarpCase, String> {
    let (dist, tilt, size) = (get(p, "dist"), get(p, "tilt").to_radians(), get(p, "size"));
    if !(dist > 0.0 && size > 0.0 && (0.0..std::f32::consts::FRAC_PI_2).contains(&tilt)) {
        return Err("need dist > 0, size > 0 and tilt in [0, 90)".into());
    }
    let center = Vec3::new(0.0, 0.0, dist);
    let eu = Vec3::new(size, 0.0, 0.0);
    let ev = Vec3::new(0.0, -tilt.cos(), tilt.sin()) * size; // eu × ev faces -z tilted about x
    let corner = center - 0.5 * (eu + ev);
    let quad = QuadLight::new(corner, eu, ev, Vec3::ONE);
    let tris = [
        Triangle::new(corner, corner + eu, corner + eu + ev),
        Triangle::new(corner, corner + eu + ev, corner + ev),
    ];
    let chart = cap_around(
        center,
        &[corner, corner + eu, corner + ev, corner + eu + ev],
    );
    let methods = LightMethods {
        quad: method,
        ..LightMethods::BASIC
    };
    Ok(light_case(
        label(name, p),
        Light::Quad(quad),
        methods,
        move |w| first_hit(&tris, w).map(|(q, _)| (q, 0)),
        chart,
    ))
}

fn first_hit(tris: &[Triangle], w: Vec3) -> Option<(Vec3, u32)> {
    let ray = Ray::new(Vec3::ZERO, w, f32::INFINITY);
    let wr = WatertightRay::new(w);
    let mut best: Option<(f32, Vec3, u32)> = None;
    for (i, t) in tris.iter().enumerate() {
        if let Some(h) = t.intersect(&ray, &wr)
            && best.is_none_or(|b| h.t < b.0)
        {
            best = Some((h.t, t.point(h.b1, h.b2), i as u32));
        }
    }
    best.map(|(_, q, i)| (q, i))
}

fn sphere_entry(name: &'static str, describe: &'static str, method: SphereMethod) -> WarpEntry {
    WarpEntry {
        name,
        describe,
        params: &[("s", 0.5), ("inside", 0.0)],
        // Tiny spheres (s = 1e-3) are the cone's case; area and cap sampling of them is
        // f32-meaningless at the silhouette and is left to the stress suite.
        suite: if matches!(method, SphereMethod::Cone) {
            &[
                &[],
                &[("s", 0.95)],
                &[("s", 0.05)],
                &[("s", 1e-3)],
                &[("s", 1e-5)],
                &[("inside", 1.0)],
            ]
        } else {
            &[&[], &[("s", 0.95)], &[("s", 0.05)], &[("inside", 1.0)]]
        },
        expect_fail: false,
        build: match method {
            SphereMethod::Area => |p| build_sphere(p, "sphere-area", SphereMethod::Area),
            SphereMethod::Cap => |p| build_sphere(p, "sphere-cap", SphereMethod::Cap),
            SphereMethod::Cone => |p| build_sphere(p, "sphere-cone", SphereMethod::Cone),
        },
    }
}

/// A unit sphere subtending sin θmax = s from the origin, or (inside = 1) containing it.
fn build_sphere(p: &Params, name: &str, method: SphereMethod) -> Result<WarpCase, String> {
    let (s, inside) = (get(p, "s"), get(p, "inside") != 0.0);
    if !(s > 0.0 && s < 1.0) {
        return Err("s must be in (0, 1)".into());
    }
    let center = if inside {
        Vec3::new(0.3, -0.2, 0.4)
    } else {
        Vec3::new(0.0, 0.0, 1.0 / s)
    };
    let light = SphereLight {
        center,
        radius: 1.0,
        radiance: Vec3::ONE,
    };
    let shape = Sphere {
        center,
        radius: 1.0,
    };
    let methods = LightMethods {
        sphere: method,
        ..LightMethods::BASIC
    };
    if inside {
        let hit = move |w: Vec3| {
            shape
                .intersect(&Ray::new(Vec3::ZERO, w, f32::INFINITY))
                .map(|t| (shape.project(w * t), 0))
        };
        return Ok(light_case(
            label(name, p),
            Light::Sphere(light),
            methods,
            hit,
            Chart::sphere(),
        ));
    }
    if method == SphereMethod::Cone {
        // The cone pdf depends on the direction alone: no re-intersection near the limb,
        // where a grazing ray/sphere hit is ill-conditioned.
        let chart = Chart::cap(center, one_minus_cos_from_sin2(s * s) as f64 * 1.02);
        return Ok(light_case(
            label(name, p),
            Light::Sphere(light),
            methods,
            move |w| Some((w, 0)),
            chart,
        ));
    }
    // Area and cap sampling are tested on the sphere's own surface, as the distribution of the
    // sampled point's normal: their solid-angle pdf ∝ 1/cos θ_l has an integrable singularity
    // at the silhouette that no direction grid can integrate, while over the surface it is
    // flat. The reported pdf is converted back from solid angle (× |cos θ_l| r²/d²), so the
    // conversion is tested as well.
    // pdf_A = pdf_ω |cos θ_l| / d², with r = 1 so the normal's density equals pdf_A.
    let to_normal = move |q: Vec3, n: Vec3, pdf_omega: f64| {
        let d = q.as_dvec3();
        pdf_omega * n.as_dvec3().dot(d).abs() / d.length().powi(3)
    };
    Ok(WarpCase {
        label: label(name, p),
        sample: Box::new(move |u| {
            let s = Light::Sphere(light).sample(Vec3::ZERO, u, &methods)?;
            Some((s.normal, to_normal(s.point, s.normal, s.pdf as f64) as f32))
        }),
        pdf: Box::new(move |n| {
            let q = center + n;
            to_normal(
                q,
                n,
                Light::Sphere(light).pdf(Vec3::ZERO, q, 0, &methods) as f64,
            )
        }),
        // Within ~1e-3 of the silhouette cos θ_l is ill-conditioned in f32 (the light's pdf
        // routine rebuilds it from q = c + n), so allow that band to disagree; the χ² test
        // still sees every sample.
        mismatch_slack: 1e-3,
        chart: Chart::cap(-center, 1.0 - 1.0 / center.length() as f64 + 1e-3),
    })
}

fn mesh_entry(name: &'static str, describe: &'static str, method: MeshMethod) -> WarpEntry {
    WarpEntry {
        name,
        describe,
        params: &[("height", 1.2)],
        suite: &[&[], &[("height", 0.3)], &[("height", 20.0)]],
        expect_fail: false,
        build: match method {
            MeshMethod::Area => |p| build_mesh(p, "mesh-area", MeshMethod::Area),
            MeshMethod::SolidAngle => |p| build_mesh(p, "mesh-solid-angle", MeshMethod::SolidAngle),
        },
    }
}

/// Four coplanar triangles of unequal area, facing down onto the origin from `height`.
fn build_mesh(p: &Params, name: &str, method: MeshMethod) -> Result<WarpCase, String> {
    let h = get(p, "height");
    if h <= 0.0 {
        return Err("height must be positive".into());
    }
    let v = [
        Vec3::new(-0.6, -0.5, h),
        Vec3::new(0.7, -0.4, h),
        Vec3::new(0.5, 0.6, h),
        Vec3::new(-0.4, 0.5, h),
        Vec3::new(0.0, 0.9, h),
        Vec3::new(-0.1, -0.9, h),
    ];
    let faces = [[0usize, 2, 1], [0, 3, 2], [3, 4, 2], [0, 1, 5]];
    let tris: Vec<Triangle> = faces
        .iter()
        .map(|f| Triangle::new(v[f[0]], v[f[1]], v[f[2]]))
        .collect();
    debug_assert!(tris.iter().all(|t| t.cross().z < 0.0));
    let light = MeshLight::new(tris.clone(), Vec3::ONE).ok_or("degenerate mesh")?;
    let chart = cap_around(Vec3::new(0.0, 0.0, h), &v);
    let methods = LightMethods {
        mesh: method,
        ..LightMethods::BASIC
    };
    Ok(light_case(
        label(name, p),
        Light::Mesh(light),
        methods,
        move |w| first_hit(&tris, w),
        chart,
    ))
}

/// One entry per (representation, sampler) of the environment light.
fn env_entries() -> Vec<WarpEntry> {
    vec![
        env_entry("env-latlong-cdf", build_env::<0, 0>),
        env_entry("env-latlong-hier", build_env::<0, 1>),
        env_entry("env-cube-cdf", build_env::<1, 0>),
        env_entry("env-cube-hier", build_env::<1, 1>),
        env_entry("env-octa-cdf", build_env::<2, 0>),
        env_entry("env-octa-hier", build_env::<2, 1>),
        env_entry("env-healpix-cdf", build_env::<3, 0>),
        env_entry("env-healpix-hier", build_env::<3, 1>),
    ]
}

fn env_entry(name: &'static str, build: fn(&Params) -> Result<WarpCase, String>) -> WarpEntry {
    WarpEntry {
        name,
        describe: "environment light importance sampling on a synthetic map (sun of relative strength `sun` + gradient + a black region), `tile` texels per tile side",
        params: &[("sun", 50.0), ("tile", 16.0)],
        suite: &[&[], &[("sun", 1e4)], &[("sun", 0.0), ("tile", 32.0)]],
        expect_fail: false,
        build,
    }
}

/// A synthetic environment: a small bright sun, a sky gradient, and a black wedge (the sampler
/// must never go there, and its pdf there must be zero).
pub fn synthetic_environment(sun: f32) -> impl Fn(Vec3) -> Vec3 + Sync {
    let sun_dir = Vec3::new(0.5, 0.6, -0.4).normalize();
    move |w: Vec3| {
        if w.x > 0.2 && w.y < 0.0 {
            return Vec3::ZERO;
        }
        let sky = Vec3::new(0.3, 0.5, 1.0) * (1.2 + w.y) + Vec3::splat(0.2 * w.z.abs());
        let s = if w.dot(sun_dir) > 0.995 { sun } else { 0.0 };
        sky + Vec3::new(1.0, 0.9, 0.7) * s
    }
}

fn build_env<const R: usize, const S: usize>(p: &Params) -> Result<WarpCase, String> {
    use crate::env::{EnvMethod, EnvSampler, Environment, Repr};
    let (sun, tile) = (get(p, "sun"), p["tile"]);
    if sun.is_nan() || sun < 0.0 {
        return Err("sun must be non-negative".into());
    }
    if !((1.0..=512.0).contains(&tile) && tile.fract() == 0.0 && (tile as usize).is_power_of_two())
    {
        return Err("tile must be a power of two in 1..=512".into());
    }
    let method = EnvMethod {
        repr: Repr::ALL[R],
        sampler: EnvSampler::ALL[S],
    };
    let n = tile as usize;
    let env = std::sync::Arc::new(Environment::build_with(&synthetic_environment(sun), [n; 4]));
    let env2 = env.clone();
    let name = crate::strategy::env_light_name(method);
    Ok(WarpCase {
        label: label(name, p),
        sample: Box::new(move |u| env.sample(method, [u[0], u[1]]).map(|s| (s.wi, s.pdf))),
        pdf: Box::new(move |w| env2.pdf(method, w) as f64),
        mismatch_slack: DEFAULT_SLACK,
        chart: Chart::sphere(),
    })
}
