//! Light selectors: every registered one (power, uniform, bvh, bvh-split, exhaustive) over
//! sets of every light type, at random shading points. The pmf sums to 1; `pmf` equals the
//! probability `sample` reports, bit for bit; the sampled light indices follow the pmf (χ²);
//! scaling the scene leaves every pmf unchanged; no light that can light the point gets pmf 0,
//! seen edge-on, straddling the horizon or behind the geometric normal of a two-sided surface
//! included. Each property is also shown to fail for the bug it is there to catch.

mod selectors_common;

use dibench::bsdf::Bsdf;
use dibench::chi2::{run_discrete, sidak};
use dibench::lights::bounds::{DistanceClamp, ImportanceModel};
use dibench::lights::selector::LightSelector;
use dibench::lights::selector::bvh::LightBvh;
use dibench::lights::selector::bvh_split::SPLIT;
use dibench::lights::selector::exhaustive::Exhaustive;
use dibench::lights::{LaneQuery, LaneQueryRows, Light, LightCtx};
use dibench::strategy::ShadingPoint;
use dibench::tracer::LANES;
use glam::Vec3;
use selectors_common::{Rng, Spec, contexts, lights, mixed, quad, selectors};

/// Σ pmf = 1 wherever `sample` can return a light (0 where it cannot), and every sampled
/// (light, p) has p == pmf(light) exactly; a selector that claims a `constant` choice returns
/// exactly it from every point.
fn consistency(
    sel: &dyn LightSelector,
    n: usize,
    ctxs: &[LightCtx],
    seed: u64,
) -> Result<(), String> {
    let mut r = Rng::new(seed);
    for (k, ctx) in ctxs.iter().enumerate() {
        let sum: f64 = (0..n).map(|i| sel.pmf(ctx, i) as f64).sum();
        let mut any = false;
        for _ in 0..16 {
            let got = sel.sample(ctx, r.u64());
            if let Some(c) = sel.constant()
                && got != Some(c)
            {
                return Err(format!("point {k}: constant {c:?} but sample gave {got:?}"));
            }
            if let Some((i, p)) = got {
                any = true;
                let q = sel.pmf(ctx, i);
                if p != q || p <= 0.0 || p.is_nan() {
                    return Err(format!(
                        "point {k}: sample gave light {i} with p {p:e}, pmf says {q:e}"
                    ));
                }
            }
        }
        let want = if any { 1.0 } else { 0.0 };
        if (sum - want).abs() > 1e-5 {
            return Err(format!(
                "point {k}: Σ pmf = {sum} (a light was sampled: {any})"
            ));
        }
    }
    Ok(())
}

#[test]
fn pmf_sums_to_one_and_equals_what_sample_reports() {
    let ctxs = contexts(3, 400);
    for (set, specs) in [
        ("local", mixed(1, 150, false)),
        ("distant too", mixed(2, 150, true)),
    ] {
        let lights = lights(&specs);
        for (name, sel) in selectors(&lights) {
            if let Err(e) = consistency(sel.as_ref(), lights.len(), &ctxs, 11) {
                panic!("{name} on {set}: {e}");
            }
        }
    }
}

/// Over one light, power and uniform selection claim their only choice as constant (the
/// light estimators then skip the per-lane call), and it is what `sample` returns; over
/// several lights no selector claims one. Negative control: a claimed constant with the
/// wrong probability.
#[test]
fn a_constant_choice_is_what_sample_returns() {
    let ctxs = contexts(5, 200);
    let one = lights(&mixed(4, 1, false));
    for (name, sel) in selectors(&one) {
        if matches!(name, "power" | "uniform") {
            assert_eq!(sel.constant().map(|c| c.0), Some(0), "{name}");
        }
        if let Err(e) = consistency(sel.as_ref(), 1, &ctxs, 13) {
            panic!("{name} over one light: {e}");
        }
    }
    let many = lights(&mixed(4, 20, false));
    for (name, sel) in selectors(&many) {
        assert_eq!(sel.constant(), None, "{name} over 20 lights");
    }
    struct Halved(Box<dyn LightSelector>);
    impl LightSelector for Halved {
        fn sample(&self, ctx: &LightCtx, u: f64) -> Option<(usize, f32)> {
            self.0.sample(ctx, u)
        }
        fn pmf(&self, ctx: &LightCtx, light: usize) -> f32 {
            self.0.pmf(ctx, light)
        }
        fn constant(&self) -> Option<(usize, f32)> {
            self.0.constant().map(|(i, p)| (i, p * 0.5))
        }
    }
    let power = (dibench::lights::selector::power::POWER.build)(&one).unwrap();
    let e = consistency(&Halved(power), 1, &ctxs, 13).unwrap_err();
    eprintln!("caught: {e}");
}

/// `sample_lanes` of a packet's lanes (some masked off) picks, lane by lane, what `sample`
/// picks from that lane's point with that lane's number, and leaves the other lanes alone.
fn lanes_agree(sel: &dyn LightSelector, ctxs: &[LightCtx], seed: u64) -> Result<(), String> {
    let mut r = Rng::new(seed);
    for (k, group) in ctxs.chunks(LANES).enumerate() {
        let mut q = LaneQueryRows::default();
        let mut u = [0.0f64; LANES];
        for (lane, ctx) in group.iter().enumerate() {
            q.p.set(lane, ctx.p);
            q.n.set(lane, ctx.n);
            u[lane] = r.u64();
        }
        let full = (1u32 << group.len()) - 1;
        // Every third packet with some lanes off.
        let mask = if k % 3 == 2 { full & 0x5a5a } else { full };
        let (mut light, mut pmf) = ([usize::MAX; LANES], [-1.0f32; LANES]);
        let picked = sel.sample_lanes(&q.query(), &u, mask, &mut light, &mut pmf);
        for lane in 0..LANES {
            let want = (mask >> lane & 1 != 0)
                .then(|| sel.sample(&q.ctx(lane), u[lane]))
                .flatten();
            let got = (picked >> lane & 1 != 0).then_some((light[lane], pmf[lane]));
            if got.map(|(i, p)| (i, p.to_bits())) != want.map(|(i, p)| (i, p.to_bits())) {
                return Err(format!(
                    "packet {k} lane {lane}: lanes {got:?}, sample {want:?}"
                ));
            }
            if picked >> lane & 1 == 0 && (light[lane], pmf[lane]) != (usize::MAX, -1.0) {
                return Err(format!(
                    "packet {k} lane {lane}: an unpicked lane was written"
                ));
            }
        }
    }
    Ok(())
}

/// Every selector's packet call is its lane-by-lane call (the light estimators ask for a
/// packet's lanes at once). Negative control: a packet call whose lanes take their
/// neighbours' numbers.
#[test]
fn sample_lanes_is_sample_lane_by_lane() {
    let ctxs = contexts(8, 320);
    for (set, specs) in [
        ("local", mixed(6, 40, false)),
        ("distant too", mixed(7, 40, true)),
    ] {
        let lights = lights(&specs);
        for (name, sel) in selectors(&lights) {
            if let Err(e) = lanes_agree(sel.as_ref(), &ctxs, 21) {
                panic!("{name} on {set}: {e}");
            }
        }
    }
    struct Shifted(Box<dyn LightSelector>);
    impl LightSelector for Shifted {
        fn sample(&self, ctx: &LightCtx, u: f64) -> Option<(usize, f32)> {
            self.0.sample(ctx, u)
        }
        fn pmf(&self, ctx: &LightCtx, light: usize) -> f32 {
            self.0.pmf(ctx, light)
        }
        fn sample_lanes(
            &self,
            q: &LaneQuery,
            u: &[f64; LANES],
            mask: u32,
            light: &mut [usize; LANES],
            pmf: &mut [f32; LANES],
        ) -> u32 {
            let shifted: [f64; LANES] = std::array::from_fn(|l| u[(l + 1) % LANES]);
            self.0.sample_lanes(q, &shifted, mask, light, pmf)
        }
    }
    let lights = lights(&mixed(6, 40, false));
    let power = (dibench::lights::selector::power::POWER.build)(&lights).unwrap();
    let e = lanes_agree(&Shifted(power), &ctxs, 21).unwrap_err();
    eprintln!("caught: {e}");
}

/// pbrt-v4's infinite-light pmf 1/(n∞ + 1) reported for lights the BVH samples by irradiance:
/// the kind of disagreement between the two halves of a selector (pbrt-v4 #163) the check is
/// for.
struct FixedInfiniteShare<'a> {
    inner: &'a dyn LightSelector,
    distant: Vec<bool>,
}

impl LightSelector for FixedInfiniteShare<'_> {
    fn sample(&self, ctx: &LightCtx, u: f64) -> Option<(usize, f32)> {
        self.inner.sample(ctx, u)
    }
    fn pmf(&self, ctx: &LightCtx, light: usize) -> f32 {
        if self.distant[light] {
            let n = self.distant.iter().filter(|&&d| d).count();
            1.0 / (n + 1) as f32
        } else {
            self.inner.pmf(ctx, light)
        }
    }
}

#[test]
fn consistency_check_catches_a_pmf_that_disagrees_with_sample() {
    let specs = mixed(2, 150, true);
    let lights = lights(&specs);
    let bvh = (dibench::lights::selector::bvh::BVH.build)(&lights).unwrap();
    let wrong = FixedInfiniteShare {
        inner: bvh.as_ref(),
        distant: specs
            .iter()
            .map(|s| matches!(s, Spec::Directional(_) | Spec::Environment(..)))
            .collect(),
    };
    let e = consistency(&wrong, lights.len(), &contexts(3, 400), 11).unwrap_err();
    eprintln!("caught: {e}");
}

/// χ² of `samples` sampled indices at `ctx` against the selector's own pmf.
fn chi2(
    sel: &dyn LightSelector,
    claimed: &dyn LightSelector,
    n: usize,
    ctx: &LightCtx,
    seed: u64,
) -> f64 {
    let pmf: Vec<f64> = (0..n).map(|i| claimed.pmf(ctx, i) as f64).collect();
    run_discrete(
        &pmf,
        |u| sel.sample(ctx, u as f64).expect("a light").0,
        200_000,
        seed,
    )
}

#[test]
fn sampled_light_indices_follow_the_pmf() {
    let sets = [mixed(4, 90, false), mixed(5, 90, true)];
    let ctxs = contexts(6, 4);
    let cases = 2 * ctxs.len() * dibench::lights::selector::SELECTORS.len();
    let alpha = sidak(0.01, cases);
    for (s, specs) in sets.iter().enumerate() {
        let lights = lights(specs);
        for (name, sel) in selectors(&lights) {
            for (k, ctx) in ctxs.iter().enumerate() {
                let p = chi2(
                    sel.as_ref(),
                    sel.as_ref(),
                    lights.len(),
                    ctx,
                    100 + k as u64,
                );
                assert!(
                    p > alpha,
                    "{name}, set {s}, point {k}: p = {p:.3e} < {alpha:.2e}"
                );
            }
        }
    }
}

/// The χ² test rejects a pmf that is not the one sampled: two entries swapped, and the
/// exhaustive selector's pmf claimed for the tree's samples.
#[test]
fn chi2_rejects_a_pmf_that_is_not_the_sampled_one() {
    let lights = lights(&mixed(4, 90, false));
    let ctx = contexts(6, 4)[1];
    let bvh = (dibench::lights::selector::bvh::BVH.build)(&lights).unwrap();
    let ex = (dibench::lights::selector::exhaustive::EXHAUSTIVE.build)(&lights).unwrap();
    assert!(chi2(bvh.as_ref(), ex.as_ref(), lights.len(), &ctx, 9) < 1e-6);
    let mut pmf: Vec<f64> = (0..lights.len()).map(|i| bvh.pmf(&ctx, i) as f64).collect();
    let big = |pmf: &[f64]| {
        let mut idx: Vec<usize> = (0..pmf.len()).collect();
        idx.sort_by(|&a, &b| pmf[b].total_cmp(&pmf[a]));
        (idx[0], idx[3])
    };
    let (a, b) = big(&pmf);
    pmf.swap(a, b);
    let p = run_discrete(&pmf, |u| bvh.sample(&ctx, u as f64).unwrap().0, 200_000, 9);
    assert!(p < 1e-6, "p = {p}");
}

/// The set scaled by `s` about the origin with radiance kept: area lights keep their
/// irradiance at scaled points; point and spot intensities scale by s² so theirs is kept too.
fn scaled(specs: &[Spec], s: f32) -> Vec<Spec> {
    specs
        .iter()
        .map(|spec| match spec.clone() {
            Spec::Quad(mut q) => {
                q = dibench::lights::quad::QuadLight::new(
                    q.corner * s,
                    q.edge_u * s,
                    q.edge_v * s,
                    q.radiance,
                );
                Spec::Quad(q)
            }
            Spec::Triangle(t) => {
                let tr = t.triangle;
                let tr =
                    dibench::geometry::triangle::Triangle::new(tr.v0 * s, tr.v1 * s, tr.v2 * s);
                Spec::Triangle(dibench::lights::mesh::TriangleLight::new(tr, t.radiance).unwrap())
            }
            Spec::Sphere(mut l) => {
                l.center *= s;
                l.radius *= s;
                Spec::Sphere(l)
            }
            Spec::Point(mut l) => {
                l.position *= s;
                l.intensity *= s * s;
                Spec::Point(l)
            }
            Spec::Spot(mut l) => {
                l.position *= s;
                l.intensity *= s * s;
                Spec::Spot(l)
            }
            Spec::Directional(mut d) => {
                d.scene_radius *= s;
                Spec::Directional(d)
            }
            Spec::Environment(c, r) => Spec::Environment(c, r * s),
        })
        .collect()
}

type Build<'a> = dyn Fn(&[Box<dyn Light>]) -> Box<dyn LightSelector> + 'a;

/// The relative pmf changes between the set and its copies scaled by 1e-3 and 1e3, over all
/// lights and points with pmf above 1e-9: (largest, 99th percentile).
fn scale_changes(build: &Build<'_>) -> (f64, f64) {
    let specs = mixed(8, 150, true);
    let base = lights(&specs);
    let sel = build(&base);
    let ctxs = contexts(9, 100);
    let mut changes = Vec::new();
    for s in [1e-3f32, 1e3] {
        let l = lights(&scaled(&specs, s));
        let sc = build(&l);
        for ctx in &ctxs {
            let c2 = LightCtx {
                p: ctx.p * s,
                n: ctx.n,
            };
            for i in 0..base.len() {
                let (a, b) = (sel.pmf(ctx, i) as f64, sc.pmf(&c2, i) as f64);
                if a.max(b) > 1e-9 {
                    changes.push((a - b).abs() / a.max(b));
                }
            }
        }
    }
    changes.sort_by(f64::total_cmp);
    (
        changes[changes.len() - 1],
        changes[changes.len() * 99 / 100],
    )
}

/// Scaled coordinates round differently in f32, and the importance amplifies that where it is
/// ill-conditioned (a light seen near grazing, cos θ′ ~ 1e-4, turns 6e-8 into ~1e-3), and a
/// tree's pmf multiplies a dozen such ratios: so every pmf within 1 %, 99 % of them within
/// 1e-4. (pbrt-v4's clamp moves 99 % of them by more than 1 %.)
#[test]
fn pmf_is_invariant_under_scaling_the_scene() {
    for s in dibench::lights::selector::SELECTORS {
        let (worst, p99) = scale_changes(&|l| (s.build)(l).unwrap());
        eprintln!(
            "{}: relative pmf change ×1e-3, ×1e3: largest {worst:.2e}, 99 % {p99:.2e}",
            s.name
        );
        assert!(
            worst < 1e-2 && p99 < 1e-4,
            "{}: pmf changes by {worst:.2e} (99 %: {p99:.2e}) when the scene is scaled",
            s.name
        );
    }
}

/// pbrt-v4's clamp d² ≥ r (a squared distance against a length) fails the same test.
#[test]
fn pbrt_v4_distance_clamp_is_not_scale_invariant() {
    let model = ImportanceModel {
        clamp: DistanceClamp::PbrtV4,
        ..ImportanceModel::STANDARD
    };
    for split in [None, Some(SPLIT)] {
        let (worst, p99) = scale_changes(&|l| Box::new(LightBvh::build(l, model, split).unwrap()));
        eprintln!("pbrt-v4 clamp, split {split:?}: largest {worst:.2e}, 99 % {p99:.2e}");
        assert!(
            worst > 0.5 && p99 > 1e-2,
            "the pbrt-v4 clamp should change the pmf"
        );
    }
}

/// Shading points that see lights edge-on (just in front of a flat light's plane, off to its
/// side), just inside a spot's cone, and beside spheres straddling their horizon, with
/// normals that put the light near the horizon.
fn hard_contexts(specs: &[Spec], seed: u64) -> Vec<LightCtx> {
    let mut r = Rng::new(seed);
    let mut v = Vec::new();
    for s in specs {
        for _ in 0..6 {
            let eps = r.log(1e-6, 1e-1);
            let ctx = match s {
                Spec::Quad(q) => {
                    let c = q.corner + 0.5 * (q.edge_u + q.edge_v);
                    let size = q.edge_u.length().max(q.edge_v.length());
                    let side = q.edge_u.normalize() * size * r.range(0.6, 4.0);
                    let p = c + side + q.normal * (eps * size);
                    LightCtx { p, n: r.dir() }
                }
                Spec::Triangle(t) => {
                    let c = (t.triangle.v0 + t.triangle.v1 + t.triangle.v2) / 3.0;
                    let size = (t.triangle.v1 - t.triangle.v0).length();
                    let side = (t.triangle.v1 - t.triangle.v0) * r.range(0.6, 4.0);
                    let p = c + side + t.normal * (eps * size);
                    LightCtx { p, n: r.dir() }
                }
                Spec::Spot(l) if r.f() < 0.5 => grazing(&mut r, l.position, eps),
                Spec::Spot(l) => {
                    let theta = (l.cos_cone.acos() * (1.0 - eps)).min(std::f32::consts::PI);
                    let f = dibench::math::Frame::from_normal(l.axis);
                    let w = f.to_world(Vec3::new(theta.sin(), 0.0, theta.cos()));
                    let p = l.position + w * r.log(0.1, 5.0);
                    LightCtx { p, n: r.dir() }
                }
                Spec::Point(l) => grazing(&mut r, l.position, eps),
                Spec::Sphere(l) => {
                    let to = r.dir();
                    let p = l.center + to * l.radius * r.log(1.0 + 1e-5, 50.0);
                    // A normal that puts the sphere's centre just below the horizon.
                    let f = dibench::math::Frame::from_normal(-to);
                    let beta = std::f32::consts::FRAC_PI_2 + eps;
                    let n = f.to_world(Vec3::new(beta.sin(), 0.0, beta.cos()));
                    LightCtx { p, n }
                }
                _ => continue,
            };
            v.push(ctx);
        }
    }
    v
}

/// A point near `x` whose normal puts x just above the horizon (by about eps·1e-3 rad, below
/// f32's resolution of directions for the smallest eps).
fn grazing(r: &mut Rng, x: Vec3, eps: f32) -> LightCtx {
    let p = x + r.dir() * r.log(0.1, 100.0);
    let to = (x - p).normalize();
    let f = dibench::math::Frame::from_normal(to);
    let beta = std::f32::consts::FRAC_PI_2 - 1e-3 * eps;
    LightCtx {
        p,
        n: f.to_world(Vec3::new(beta.sin(), 0.0, beta.cos())),
    }
}

/// (context, light) pairs where the light can light the point but the selector says pmf 0.
fn zero_pmf_for_contributing(
    sel: &dyn LightSelector,
    specs: &[Spec],
    ctxs: &[LightCtx],
) -> Vec<String> {
    let mut bad = Vec::new();
    for (k, ctx) in ctxs.iter().enumerate() {
        for (i, s) in specs.iter().enumerate() {
            if s.contributes(ctx.p, ctx.n) && sel.pmf(ctx, i) == 0.0 {
                bad.push(format!("point {k} {ctx:?}: light {i} {s:?}"));
            }
        }
    }
    bad
}

#[test]
fn no_light_that_contributes_gets_pmf_zero() {
    let specs = mixed(12, 300, true);
    let lights = lights(&specs);
    let mut ctxs = contexts(13, 300);
    ctxs.extend(hard_contexts(&specs, 14));
    for (name, sel) in selectors(&lights) {
        let bad = zero_pmf_for_contributing(sel.as_ref(), &specs, &ctxs);
        assert!(
            bad.is_empty(),
            "{name}: {} contributing lights with pmf 0, e.g. {}",
            bad.len(),
            bad[0]
        );
    }
    // Some lights are provably dark at some points (behind, below the horizon): the tree
    // and exhaustive selectors give those 0, so the check above is not vacuous.
    let ex = (dibench::lights::selector::exhaustive::EXHAUSTIVE.build)(&lights).unwrap();
    let zeros = ctxs
        .iter()
        .flat_map(|c| (0..lights.len()).map(move |i| (c, i)))
        .filter(|&(c, i)| ex.pmf(c, i) == 0.0)
        .count();
    assert!(zeros > 1000, "only {zeros} zero pmfs");
}

/// Without the rounding safeguards (no angular pad, no slack on the bounding sphere) the
/// importance rounds some lights seen edge-on to 0: the check above catches it.
#[test]
fn without_rounding_safeguards_edge_on_lights_get_pmf_zero() {
    let specs = mixed(12, 300, true);
    let lights = lights(&specs);
    let ctxs = hard_contexts(&specs, 14);
    let raw = ImportanceModel {
        angle_pad: 0.0,
        slack_ulps: 0.0,
        ..ImportanceModel::STANDARD
    };
    let bounds: Vec<_> = lights.iter().map(|l| l.bounds()).collect();
    let ex = Exhaustive::build(&bounds, raw).unwrap();
    let bad = zero_pmf_for_contributing(&ex, &specs, &ctxs);
    eprintln!(
        "{} contributing lights with pmf 0, e.g. {:?}",
        bad.len(),
        bad.first()
    );
    assert!(!bad.is_empty());
}

/// A two-sided surface seen from the side its geometric normal points away from: the shading
/// normal is flipped to the viewer (`ShadingPoint::with_error`), and a light on that side must
/// be selectable. A selector given the geometric normal instead would never pick it.
#[test]
fn lights_behind_the_geometric_normal_are_selectable() {
    let down = quad(
        Vec3::new(0.3, 2.0, -0.2),
        -Vec3::Y,
        0.5,
        0.4,
        Vec3::splat(5.0),
    );
    let far = quad(
        Vec3::new(4.0, -3.0, 1.0),
        Vec3::new(-1.0, 1.0, 0.0).normalize(),
        0.5,
        0.5,
        Vec3::ONE,
    );
    let specs = vec![Spec::Quad(down), Spec::Quad(far)];
    let lights = lights(&specs);
    let bsdf = Bsdf::lambertian(Vec3::splat(0.5));
    // Geometric normal -y, viewed from above: the shading normal becomes +y.
    let ng = -Vec3::Y;
    let sp = ShadingPoint::with_error(Vec3::ZERO, Vec3::splat(1e-7), ng, -Vec3::Y, &bsdf);
    assert_eq!(sp.n, Vec3::Y);
    let flipped = sp.light_ctx();
    let geometric = LightCtx { p: sp.p, n: ng };
    assert!(specs[0].contributes(flipped.p, flipped.n));
    for (name, sel) in selectors(&lights) {
        assert!(
            sel.pmf(&flipped, 0) > 0.0,
            "{name}: the light above gets pmf 0"
        );
    }
    for name in ["bvh", "bvh-split", "exhaustive"] {
        let sel = (dibench::lights::selector::by_name(name).unwrap().build)(&lights).unwrap();
        assert_eq!(
            sel.pmf(&geometric, 0),
            0.0,
            "{name}: the negative control has no teeth"
        );
    }
}
