//! A light BVH (Conty Estevez & Kulla 2018; pbrt-v4 `BVHLightSampler`): a binary tree over the
//! lights at finite places, each node bounding its lights' positions, normals and intensity;
//! a sample descends from the root choosing each child in proportion to its importance at the
//! shading point ([`CompactBounds::importance`]), one light per leaf. Lights at infinity stay
//! out of the tree and compete with its root at the top, each by the irradiance it delivers
//! (pbrt-v4 gives them a fixed n∞/(n∞+1) whatever they deliver).
//!
//! Built top-down by 12-bucket binning with Conty Estevez & Kulla's cost (intensity ×
//! orientation measure M_Ω × box area × pbrt-v4's K_r for thin boxes), iteratively (no
//! recursion however deep the tree: skewed inputs reach depth > 32). Nodes are stored depth
//! first, the left child after its parent, so the subtree of a node is the index range up to
//! its right child: `pmf` finds its way down to a light's leaf by comparing leaf indices,
//! with no per-light bit trail (pbrt-v4's 32-bit trail is shifted by the depth, which its
//! build only bounds by 64) and no parent links. Where both children of a node have importance
//! 0 — none of its lights can reach the point — the descent goes on with probability 1/2 each,
//! so the pmf over all lights still sums to 1 (pbrt-v4 returns no light there).
//!
//! The selection number is an f64 with 48 random bits (`lights::selection_number`): each
//! level rescales it, and 24 bits would be gone after 24 binary choices.

use super::{LightSelector, SelectorType, remap};
use crate::lights::bounds::{
    Bounds, BoundsSum, CompactBounds, DistantBounds, ImportanceModel, orientation_measure,
};
use crate::lights::{Light, LightCtx};
use glam::Vec3;

pub static BVH: SelectorType = SelectorType {
    name: "bvh",
    describe: "light BVH: descend by each node's importance bound at the point (Conty Estevez & Kulla 2018)",
    build: |lights| {
        LightBvh::build(lights, ImportanceModel::STANDARD, None)
            .map(|b| Box::new(b) as Box<dyn LightSelector>)
    },
};

/// Buckets per axis when choosing a split (pbrt-v4's 12).
const BUCKETS: usize = 12;
const LEAF: u32 = 1 << 31;
/// The least probability a child with positive importance is chosen with: a share below
/// f64's 2^-53 would otherwise round a light that can contribute to pmf 0.
const MIN_SHARE: f64 = 1.0 / (1u64 << 40) as f64;

/// A selected light with its pmf, unless the pmf is below f32's range: a light whose
/// selection probability is under 1e-38 is never returned, and its `pmf` is 0 to match.
#[inline]
pub(super) fn positive(light: usize, pmf: f64) -> Option<(usize, f32)> {
    let p = pmf as f32;
    (p > 0.0).then_some((light, p))
}

/// Where the importance bound of a node is loose, replace it by the sum over its children's
/// (recursively, at most `depth` levels down): the one-sample form of Conty Estevez & Kulla's
/// adaptive splitting, which takes one sample in each part of a split and sums them. A node is
/// loose when the shading point lies within `1/min_sin` of its bounding radius (the sphere
/// subtends more than asin(min_sin)): there the 1/d² factor varies by more than
/// ((1 + s)/(1 − s))² over the node, and p inside bounds nothing at all.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    pub min_sin: f32,
    pub depth: u32,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: CompactBounds,
    /// Interior: index of the right child (the left one follows the node). Leaf: LEAF | light.
    child: u32,
}

impl Node {
    fn leaf_light(&self) -> Option<usize> {
        (self.child & LEAF != 0).then_some((self.child & !LEAF) as usize)
    }
}

/// Build-time numbers, for reports and tests.
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildStats {
    pub lights_in_tree: usize,
    pub distant: usize,
    pub nodes: usize,
    pub depth: usize,
    /// Memory of the tree and the per-light tables [bytes].
    pub bytes: usize,
}

pub struct LightBvh {
    nodes: Vec<Node>,
    /// Leaf node of each light; `u32::MAX` for lights outside the tree.
    leaf_of: Vec<u32>,
    /// Lights at infinity (light index, bounds), chosen beside the tree's root.
    distant: Vec<(u32, DistantBounds)>,
    /// Each light's place among the distant ones, `u32::MAX` for others.
    distant_of: Vec<u32>,
    model: ImportanceModel,
    split: Option<Split>,
    stats: BuildStats,
}

struct Item {
    light: u32,
    /// The light's own bounds, as a sum of one (its cone ready for unions).
    bounds: BoundsSum,
    centroid: Vec3,
}

struct Task {
    start: usize,
    end: usize,
    sum: BoundsSum,
    depth: usize,
    /// Its node's index in the slice being built.
    at: usize,
}

impl LightBvh {
    /// The tree over `lights` with importance `model` (ImportanceModel::STANDARD but for
    /// tests) and optional splitting; Err when no light has positive intensity or irradiance.
    pub fn build(
        lights: &[Box<dyn Light>],
        model: ImportanceModel,
        split: Option<Split>,
    ) -> Result<Self, String> {
        if lights.len() >= LEAF as usize {
            return Err(format!("{} lights: more than a light BVH indexes", lights.len()));
        }
        let mut items = Vec::new();
        let mut distant = Vec::new();
        let mut distant_of = vec![u32::MAX; lights.len()];
        for (i, l) in lights.iter().enumerate() {
            match l.bounds() {
                Bounds::Local(b) if b.intensity > 0.0 => items.push(Item {
                    light: i as u32,
                    centroid: b.centroid(),
                    bounds: BoundsSum::of(&b),
                }),
                Bounds::Distant(d) if d.irradiance > 0.0 => {
                    distant_of[i] = distant.len() as u32;
                    distant.push((i as u32, d));
                }
                _ => {}
            }
        }
        if items.is_empty() && distant.is_empty() {
            return Err("no light with positive intensity".into());
        }
        let mut leaf_of = vec![u32::MAX; lights.len()];
        let (nodes, depth) = build_nodes(&mut items, &mut leaf_of);
        let stats = BuildStats {
            lights_in_tree: items.len(),
            distant: distant.len(),
            nodes: nodes.len(),
            depth,
            bytes: nodes.capacity() * std::mem::size_of::<Node>()
                + leaf_of.capacity() * 4
                + distant_of.capacity() * 4
                + distant.capacity() * std::mem::size_of::<(u32, DistantBounds)>(),
        };
        Ok(LightBvh {
            nodes,
            leaf_of,
            distant,
            distant_of,
            model,
            split,
            stats,
        })
    }

    pub fn stats(&self) -> BuildStats {
        self.stats
    }

    /// The importance of node k at the point, refined where splitting asks for it.
    #[inline]
    fn importance(&self, k: usize, p: Vec3, n: Vec3) -> f64 {
        match self.split {
            None => self.nodes[k].bounds.importance_with(p, n, &self.model),
            Some(s) => self.refined(k, p, n, s, s.depth),
        }
    }

    fn refined(&self, k: usize, p: Vec3, n: Vec3, s: Split, depth: u32) -> f64 {
        let node = &self.nodes[k];
        let b = &node.bounds;
        let loose = depth > 0
            && node.leaf_light().is_none()
            && b.radius * b.radius >= s.min_sin * s.min_sin * (b.center - p).length_squared();
        if !loose {
            return b.importance_with(p, n, &self.model);
        }
        self.refined(k + 1, p, n, s, depth - 1)
            + self.refined(node.child as usize, p, n, s, depth - 1)
    }

    /// The top-level weights: the tree's root (if any), then each distant light.
    #[inline]
    fn top(&self, ctx: &LightCtx) -> (f64, f64) {
        let root = if self.nodes.is_empty() {
            0.0
        } else {
            self.importance(0, ctx.p, ctx.n)
        };
        let distant: f64 = self.distant.iter().map(|(_, d)| d.importance(ctx.n)).sum();
        (root, distant)
    }

    /// Probability of going left at interior node k, and the child indices.
    #[inline]
    fn split_at(&self, k: usize, ctx: &LightCtx) -> (f64, usize, usize) {
        let right = self.nodes[k].child as usize;
        let il = self.importance(k + 1, ctx.p, ctx.n);
        let ir = self.importance(right, ctx.p, ctx.n);
        let total = il + ir;
        let mut pl = if total > 0.0 { il / total } else { 0.5 };
        // A child that may light the point keeps a share f64 can carry through a deep path.
        if il > 0.0 {
            pl = pl.max(MIN_SHARE);
        }
        if ir > 0.0 {
            pl = pl.min(1.0 - MIN_SHARE);
        }
        (pl, k + 1, right)
    }

    /// The light a path of choices (true: right) leads to from the root and the probability
    /// of that path at `ctx`, the root's top-level share included; stops at the first leaf.
    pub fn path_pmf(&self, ctx: &LightCtx, path: impl IntoIterator<Item = bool>) -> (usize, f32) {
        let (root, distant) = self.top(ctx);
        let mut pmf = if root > 0.0 { root / (root + distant) } else { 0.0 };
        let mut k = 0;
        let mut path = path.into_iter();
        loop {
            if let Some(light) = self.nodes[k].leaf_light() {
                return (light, pmf as f32);
            }
            let (pl, l, r) = self.split_at(k, ctx);
            if path.next().unwrap_or(false) {
                pmf *= 1.0 - pl;
                k = r;
            } else {
                pmf *= pl;
                k = l;
            }
        }
    }

    /// The choices (true: right) from the root to `light`'s leaf; None outside the tree.
    pub fn path(&self, light: usize) -> Option<Vec<bool>> {
        let target = *self.leaf_of.get(light).filter(|&&t| t != u32::MAX)? as usize;
        let mut k = 0;
        let mut path = Vec::new();
        while self.nodes[k].leaf_light().is_none() {
            let right = self.nodes[k].child as usize;
            let go_right = target >= right;
            path.push(go_right);
            k = if go_right { right } else { k + 1 };
        }
        Some(path)
    }
}

impl LightSelector for LightBvh {
    fn sample(&self, ctx: &LightCtx, u: f64) -> Option<(usize, f32)> {
        let (root, distant) = self.top(ctx);
        let total = root + distant;
        if total <= 0.0 {
            return None;
        }
        // The root's share of [0, total) first, then the distant lights' in order.
        let target = u * total;
        if target >= root {
            let mut acc = root;
            let mut last = None;
            for &(light, d) in &self.distant {
                let w = d.importance(ctx.n);
                if w > 0.0 {
                    last = Some((light as usize, w));
                    if target < acc + w {
                        break;
                    }
                    acc += w;
                }
            }
            // Rounding can put u·total past the last share: it belongs to the last one.
            if let Some((light, w)) = last {
                return positive(light, w / total);
            }
        }
        let mut u = (target / root).min(1.0 - f64::EPSILON / 2.0);
        let mut pmf = root / total;
        let mut k = 0;
        loop {
            if let Some(light) = self.nodes[k].leaf_light() {
                return positive(light, pmf);
            }
            let (pl, l, r) = self.split_at(k, ctx);
            if u < pl {
                u = remap(u, 0.0, pl);
                pmf *= pl;
                k = l;
            } else {
                u = remap(u, pl, 1.0 - pl);
                pmf *= 1.0 - pl;
                k = r;
            }
        }
    }

    fn pmf(&self, ctx: &LightCtx, light: usize) -> f32 {
        let (root, distant) = self.top(ctx);
        let total = root + distant;
        if total <= 0.0 {
            return 0.0;
        }
        if let Some(&d) = self.distant_of.get(light).filter(|&&d| d != u32::MAX) {
            return (self.distant[d as usize].1.importance(ctx.n) / total) as f32;
        }
        let Some(&target) = self.leaf_of.get(light).filter(|&&t| t != u32::MAX) else {
            return 0.0;
        };
        let target = target as usize;
        let mut pmf = root / total;
        let mut k = 0;
        while self.nodes[k].leaf_light().is_none() {
            let (pl, l, r) = self.split_at(k, ctx);
            if target < r {
                pmf *= pl;
                k = l;
            } else {
                pmf *= 1.0 - pl;
                k = r;
            }
        }
        pmf as f32
    }
}

/// The bucket of a centroid coordinate along an axis of extent `extent` from `lo`; the same
/// expression bins and partitions.
#[inline]
fn bucket(c: f32, lo: f32, extent: f32) -> usize {
    (((c - lo) / extent * BUCKETS as f32) as usize).min(BUCKETS - 1)
}

/// Conty Estevez & Kulla's cost of a cluster: intensity × M_Ω × area (the K_r factor is the
/// axis's, applied by the caller).
fn cost(s: &BoundsSum) -> f64 {
    s.intensity * orientation_measure(s.cone.theta, s.theta_e) * s.area_measure()
}

/// Ranges at least this large split on two threads (rayon), above depth 32 never.
const PARALLEL_MIN: usize = 1 << 15;

/// The nodes, depth first, and the tree's depth; fills `leaf_of`. A subtree over m lights
/// takes exactly 2m − 1 nodes, so every subtree's place is known before it is built: the two
/// halves of a split are built into disjoint slices, in parallel for large ones, and the
/// result does not depend on the thread schedule.
fn build_nodes(items: &mut [Item], leaf_of: &mut [u32]) -> (Vec<Node>, usize) {
    if items.is_empty() {
        return (Vec::new(), 0);
    }
    let mut root = BoundsSum::default();
    for it in items.iter() {
        root.merge(&it.bounds);
    }
    let blank = Node {
        bounds: CompactBounds::new(&root.bounds()),
        child: 0,
    };
    let mut nodes = vec![blank; 2 * items.len() - 1];
    let depth = build_into(&mut nodes, 0, items, root, 0);
    for (k, n) in nodes.iter().enumerate() {
        if let Some(light) = n.leaf_light() {
            leaf_of[light] = k as u32;
        }
    }
    (nodes, depth)
}

/// The subtree over `items` with bounds `sum` into `nodes` (2·len − 1 of them; the first is
/// node `base` of the tree), at depth `depth`; returns the deepest leaf's depth.
fn build_into(
    nodes: &mut [Node],
    base: usize,
    items: &mut [Item],
    sum: BoundsSum,
    depth: usize,
) -> usize {
    if items.len() >= PARALLEL_MIN && depth < 32 {
        let (mid, left, right) = split(items, &sum);
        let (head, rest) = nodes.split_first_mut().expect("2·len − 1 > 0 nodes");
        *head = Node {
            bounds: CompactBounds::new(&sum.bounds()),
            child: (base + 2 * mid) as u32,
        };
        let (ln, rn) = rest.split_at_mut(2 * mid - 1);
        let (li, ri) = items.split_at_mut(mid);
        let (a, b) = rayon::join(
            || build_into(ln, base + 1, li, left, depth + 1),
            || build_into(rn, base + 2 * mid, ri, right, depth + 1),
        );
        return a.max(b);
    }
    // Below: one thread, an explicit stack (no recursion however deep the tree gets).
    let mut stack = vec![Task {
        start: 0,
        end: items.len(),
        sum,
        depth,
        at: 0,
    }];
    let mut max_depth = depth;
    while let Some(t) = stack.pop() {
        max_depth = max_depth.max(t.depth);
        if t.end - t.start == 1 {
            let it = &items[t.start];
            nodes[t.at] = Node {
                bounds: CompactBounds::new(&it.bounds.bounds()),
                child: LEAF | it.light,
            };
            continue;
        }
        let (mid, left, right) = split(&mut items[t.start..t.end], &t.sum);
        nodes[t.at] = Node {
            bounds: CompactBounds::new(&t.sum.bounds()),
            child: (base + t.at + 2 * mid) as u32,
        };
        stack.push(Task {
            start: t.start + mid,
            end: t.end,
            sum: right,
            depth: t.depth + 1,
            at: t.at + 2 * mid,
        });
        stack.push(Task {
            start: t.start,
            end: t.start + mid,
            sum: left,
            depth: t.depth + 1,
            at: t.at + 1,
        });
    }
    max_depth
}

/// Partitions `items` (at least two) at the cheapest of the 11 bucket boundaries on each axis
/// where the centroids spread; returns the split position and both sides' bounds. Where every
/// centroid coincides, or no boundary has lights on both sides, splits the range in half.
fn split(items: &mut [Item], sum: &BoundsSum) -> (usize, BoundsSum, BoundsSum) {
    let (clo, chi) = items
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), it| {
            (lo.min(it.centroid), hi.max(it.centroid))
        });
    let box_extent = (sum.hi - sum.lo).max(Vec3::ZERO);
    let mut best: Option<(f64, usize, usize, BoundsSum, BoundsSum)> = None;
    for dim in 0..3 {
        let extent = chi[dim] - clo[dim];
        if extent <= 0.0 {
            continue;
        }
        let mut buckets = [BoundsSum::default(); BUCKETS];
        for it in items.iter() {
            buckets[bucket(it.centroid[dim], clo[dim], extent)].merge(&it.bounds);
        }
        let mut below = [BoundsSum::default(); BUCKETS - 1];
        let mut acc = BoundsSum::default();
        for i in 0..BUCKETS - 1 {
            acc.merge(&buckets[i]);
            below[i] = acc;
        }
        // K_r (pbrt-v4): splitting a box across its thin side is penalised.
        let kr = (box_extent.max_element() / box_extent[dim]) as f64;
        let mut above = BoundsSum::default();
        for i in (0..BUCKETS - 1).rev() {
            above.merge(&buckets[i + 1]);
            // After an empty bucket the partition is the previous boundary's.
            if below[i].count == 0 || above.count == 0 || buckets[i].count == 0 {
                continue;
            }
            let c = kr * (cost(&below[i]) + cost(&above));
            if best.as_ref().is_none_or(|b| c < b.0) {
                best = Some((c, dim, i, below[i], above));
            }
        }
    }
    let Some((_, dim, boundary, left, right)) = best else {
        let mid = items.len() / 2;
        let mut left = BoundsSum::default();
        let mut right = BoundsSum::default();
        for it in &items[..mid] {
            left.merge(&it.bounds);
        }
        for it in &items[mid..] {
            right.merge(&it.bounds);
        }
        return (mid, left, right);
    };
    let (lo, extent) = (clo[dim], chi[dim] - clo[dim]);
    let mut mid = 0;
    for i in 0..items.len() {
        if bucket(items[i].centroid[dim], lo, extent) <= boundary {
            items.swap(i, mid);
            mid += 1;
        }
    }
    (mid, left, right)
}
