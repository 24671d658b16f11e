//! The wide BVH: obvhs builds a binary tree (PLOC + SAH reinsertion, one primitive per leaf), and
//! it is collapsed here into 8-wide nodes with structure-of-arrays child boxes and leaves of up
//! to 8 triangles stored as one SoA block, so one 8-lane sequence tests all children of a node
//! or all triangles of a leaf.
//!
//! Collapse: the dynamic program of Ylitie, Karras and Laine (HPG 2017, §4.1) over the binary
//! tree, minimising the surface-area cost of the wide tree: each wide node costs its area times
//! the cost of one 8-child test, each leaf its area times the cost of one block test (8
//! triangles at once), and a binary subtree may become one leaf (≤ 8 triangles), one wide node,
//! or be spread over several of its parent's 8 child slots. Child boxes are the binary nodes'
//! boxes, unchanged.

use crate::error::{Error, Result};
use crate::simd::NARROW;
use crate::tracer::Geometry;
use crate::tracer::bvh::build_bvh2;
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use std::time::{Duration, Instant};

/// Children per node and triangles per leaf block.
pub const BRANCH: usize = NARROW;

/// A child reference: an inner node, a leaf block of 1–8 triangles, one sphere, or empty.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct Child(pub u32);

const LEAF: u32 = 1 << 31;
const SPHERE: u32 = 1 << 30;
const COUNT_SHIFT: u32 = 27;
const INDEX_BITS: u32 = (1 << COUNT_SHIFT) - 1;

/// What a [`Child`] refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Inner(u32),
    /// Block index and triangle count (1..=8).
    Block(u32, u32),
    /// Primitive id of a sphere.
    Sphere(u32),
    Empty,
}

impl Child {
    pub const EMPTY: Child = Child(u32::MAX);

    fn inner(i: usize) -> Result<Child> {
        if i as u64 >= SPHERE as u64 {
            return Err(Error::Backend(format!(
                "packet backend: {i} nodes exceed 2^30"
            )));
        }
        Ok(Child(i as u32))
    }

    fn block(i: usize, count: usize) -> Result<Child> {
        debug_assert!((1..=BRANCH).contains(&count));
        if i as u64 > INDEX_BITS as u64 {
            return Err(Error::Backend(format!(
                "packet backend: {i} leaf blocks exceed 2^27"
            )));
        }
        Ok(Child(LEAF | ((count as u32 - 1) << COUNT_SHIFT) | i as u32))
    }

    fn sphere(prim: u32) -> Result<Child> {
        if prim >= SPHERE {
            return Err(Error::Backend(format!(
                "packet backend: primitive id {prim} exceeds 2^30"
            )));
        }
        Ok(Child(LEAF | SPHERE | prim))
    }

    #[inline(always)]
    pub fn is_inner(self) -> bool {
        self.0 & LEAF == 0
    }

    #[inline(always)]
    pub fn kind(self) -> Kind {
        if self.0 & LEAF == 0 {
            Kind::Inner(self.0)
        } else if self == Child::EMPTY {
            Kind::Empty
        } else if self.0 & SPHERE != 0 {
            Kind::Sphere(self.0 & !(LEAF | SPHERE))
        } else {
            Kind::Block(self.0 & INDEX_BITS, ((self.0 >> COUNT_SHIFT) & 7) + 1)
        }
    }
}

/// Box plane rows of [`Node::b`]: `b[axis]` holds the minima, `b[3 + axis]` the maxima.
pub const MAX_ROW: usize = 3;

/// An 8-wide node: child boxes as structure of arrays. Empty slots hold the inverted box
/// (min = +∞, max = −∞), which a slab test picking near/far planes by the ray's direction
/// sign always misses; children are packed at the front (`count` of them).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Node {
    pub b: [[f32; BRANCH]; 6],
    pub child: [Child; BRANCH],
    pub count: u32,
}

/// Up to 8 triangles, structure of arrays: `v[vertex][axis][lane]`, and their primitive ids.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct Block {
    pub v: [[[f32; BRANCH]; 3]; 3],
    pub prim: [u32; BRANCH],
}

/// Build knobs: the obvhs preset for the binary tree, and the relative SAH costs of an 8-wide
/// node test and of a leaf-block test per unit of surface area.
#[derive(Clone, Copy, Debug)]
pub struct BuildParams {
    pub preset: BvhBuildParams,
    pub node_cost: f32,
    pub block_cost: f32,
}

impl Default for BuildParams {
    /// Measured on bunny and the dragon (`DIBENCH_BUILD_SWEEP=1 cargo bench --bench rays`;
    /// docs/tracer.md, stop 39): obvhs's medium preset with reinsertion (Meister and Bittner
    /// 2018) offered to every node rather than 5 % of them, which traces shadow and
    /// incoherent rays 4–7 % faster for an 8× longer build (the dragon: 1.2 s against 0.15 s);
    /// one primitive per binary leaf so the block decision is ours.
    fn default() -> Self {
        BuildParams {
            preset: BvhBuildParams {
                max_prims_per_leaf: 1,
                reinsertion_batch_ratio: 1.0,
                post_collapse_reinsertion_batch_ratio_multiplier: 1.0,
                ..BvhBuildParams::medium_build()
            },
            node_cost: 1.0,
            block_cost: 1.5,
        }
    }
}

pub struct Wide {
    pub nodes: Vec<Node>,
    pub blocks: Vec<Block>,
    pub root: Child,
    /// Levels of inner nodes on the deepest path.
    pub depth: usize,
    pub build_time: Duration,
}

impl Wide {
    /// Starts the memory reads of a child's node or leaf block (see [`crate::simd::prefetch`]).
    #[inline(always)]
    pub fn prefetch(&self, c: Child) {
        match c.kind() {
            Kind::Inner(i) => crate::simd::prefetch(self.nodes.as_ptr().wrapping_add(i as usize)),
            Kind::Block(b, _) => {
                crate::simd::prefetch(self.blocks.as_ptr().wrapping_add(b as usize))
            }
            Kind::Sphere(_) | Kind::Empty => {}
        }
    }
}

/// Slots of a wide node.
const SLOTS: usize = BRANCH;

/// The dynamic program's choice for one binary node.
#[derive(Clone, Copy, Default)]
struct Choice {
    /// Triangles below (saturating past a block), spheres below.
    tris: u32,
    spheres: u32,
    /// As one child of its parent: a leaf (else a wide node).
    leaf: bool,
    /// `cost[j-1]`: least cost of the subtree spread over at most j child slots.
    cost: [f32; SLOTS],
    /// `split[j-1]`: 0 = one child (leaf or node), else slots given to the left subtree.
    split: [u8; SLOTS],
}

struct Collapser<'a> {
    bvh: &'a Bvh2,
    geometry: &'a Geometry,
    dp: Vec<Choice>,
    out: Wide,
}

fn half_area(b: &Aabb) -> f32 {
    let d = b.max - b.min;
    (d.x * d.y + d.y * d.z + d.z * d.x).max(0.0)
}

impl Collapser<'_> {
    fn is_sphere(&self, slot: u32) -> bool {
        self.geometry
            .sphere_index(self.bvh.primitive_indices[slot as usize])
            .is_some()
    }

    /// Best split of at most `j` slots between the children of binary node `n`.
    fn spread(&self, n: usize, j: usize) -> (f32, u8) {
        let first = self.bvh.nodes[n].first_index as usize;
        let (l, r) = (&self.dp[first], &self.dp[first + 1]);
        let mut best = (f32::INFINITY, 0);
        for k in 1..j {
            let c = l.cost[k - 1] + r.cost[j - k - 1];
            if c < best.0 {
                best = (c, k as u8);
            }
        }
        best
    }

    /// Bottom-up: the costs and choices of every binary node.
    fn solve(&mut self, p: &BuildParams) {
        let nodes = &self.bvh.nodes;
        let mut order = Vec::with_capacity(nodes.len());
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            order.push(i);
            let n = &nodes[i];
            if n.prim_count == 0 {
                stack.push(n.first_index as usize);
                stack.push(n.first_index as usize + 1);
            }
        }
        for &i in order.iter().rev() {
            let n = &nodes[i];
            let area = half_area(&n.aabb);
            let mut c = Choice::default();
            if n.prim_count > 0 {
                for slot in n.first_index..n.first_index + n.prim_count {
                    if self.is_sphere(slot) {
                        c.spheres += 1;
                    } else {
                        c.tris += 1;
                    }
                }
                c.leaf = true;
                let blocks = c.tris.div_ceil(BRANCH as u32) + c.spheres;
                c.cost = [area * p.block_cost * blocks as f32; SLOTS];
            } else {
                let first = n.first_index as usize;
                let (l, r) = (&self.dp[first], &self.dp[first + 1]);
                c.tris = (l.tris + r.tris).min(BRANCH as u32 + 1);
                c.spheres = (l.spheres + r.spheres).min(2);
                let fits = c.spheres == 0 && c.tris as usize <= BRANCH;
                let as_leaf = if fits {
                    area * p.block_cost
                } else {
                    f32::INFINITY
                };
                let as_node = area * p.node_cost + self.spread(i, SLOTS).0;
                c.leaf = as_leaf <= as_node;
                let one = as_leaf.min(as_node);
                c.cost[0] = one;
                for j in 2..=SLOTS {
                    let (spread, k) = self.spread(i, j);
                    (c.cost[j - 1], c.split[j - 1]) =
                        if one <= spread { (one, 0) } else { (spread, k) };
                }
            }
            self.dp[i] = c;
        }
    }

    /// The binary subtrees that take the (at most `j`) slots `n` is given.
    fn subtrees(&self, n: usize, j: usize, out: &mut Vec<usize>) {
        match self.dp[n].split[j - 1] {
            0 => out.push(n),
            k => {
                let first = self.bvh.nodes[n].first_index as usize;
                self.subtrees(first, k as usize, out);
                self.subtrees(first + 1, j - k as usize, out);
            }
        }
    }

    /// Slots of the primitives below binary node `i`.
    fn slots(&self, i: usize, out: &mut Vec<u32>) {
        let n = &self.bvh.nodes[i];
        if n.prim_count > 0 {
            out.extend(n.first_index..n.first_index + n.prim_count);
        } else {
            self.slots(n.first_index as usize, out);
            self.slots(n.first_index as usize + 1, out);
        }
    }

    /// A leaf child for binary node `i` (the program made it one).
    fn leaf(&mut self, i: usize) -> Result<Child> {
        let mut slots = vec![];
        self.slots(i, &mut slots);
        let prims: Vec<u32> = slots
            .iter()
            .map(|&s| self.bvh.primitive_indices[s as usize])
            .collect();
        if let [p] = prims[..]
            && self.geometry.sphere_index(p).is_some()
        {
            return Child::sphere(p);
        }
        if prims.len() > BRANCH
            || prims
                .iter()
                .any(|&p| self.geometry.sphere_index(p).is_some())
        {
            return Err(Error::Backend(
                "packet backend: obvhs returned a leaf the collapse cannot store".into(),
            ));
        }
        let mut block = Block {
            v: [[[0.0; BRANCH]; 3]; 3],
            prim: [0; BRANCH],
        };
        for (lane, &p) in prims.iter().enumerate() {
            let t = &self.geometry.triangles[p as usize];
            for (k, v) in [t.v0, t.v1, t.v2].into_iter().enumerate() {
                for a in 0..3 {
                    block.v[k][a][lane] = v[a];
                }
            }
            block.prim[lane] = p;
        }
        self.out.blocks.push(block);
        Child::block(self.out.blocks.len() - 1, prims.len())
    }

    /// The child for binary node `i`: a leaf, or a new wide node over the subtrees the program
    /// spread its 8 slots over.
    fn child(&mut self, i: usize, depth: usize) -> Result<Child> {
        if self.dp[i].leaf {
            return self.leaf(i);
        }
        let first = self.bvh.nodes[i].first_index as usize;
        let k = self.spread(i, SLOTS).1 as usize;
        let mut kids = vec![];
        self.subtrees(first, k, &mut kids);
        self.subtrees(first + 1, SLOTS - k, &mut kids);
        let index = self.out.nodes.len();
        self.out.nodes.push(Node {
            b: [
                [f32::INFINITY; BRANCH],
                [f32::INFINITY; BRANCH],
                [f32::INFINITY; BRANCH],
                [f32::NEG_INFINITY; BRANCH],
                [f32::NEG_INFINITY; BRANCH],
                [f32::NEG_INFINITY; BRANCH],
            ],
            child: [Child::EMPTY; BRANCH],
            count: kids.len() as u32,
        });
        self.out.depth = self.out.depth.max(depth + 1);
        for (slot, &k) in kids.iter().enumerate() {
            let c = self.child(k, depth + 1)?;
            let (lo, hi) = (self.bvh.nodes[k].aabb.min, self.bvh.nodes[k].aabb.max);
            let n = &mut self.out.nodes[index];
            for a in 0..3 {
                n.b[a][slot] = lo[a];
                n.b[MAX_ROW + a][slot] = hi[a];
            }
            n.child[slot] = c;
        }
        Child::inner(index)
    }
}

impl Wide {
    /// Builds the wide BVH over the geometry; an empty scene gets an empty root.
    pub fn build(geometry: &Geometry, p: &BuildParams) -> Result<Wide> {
        let start = Instant::now();
        let mut out = Wide {
            nodes: vec![],
            blocks: vec![],
            root: Child::EMPTY,
            depth: 0,
            build_time: Duration::ZERO,
        };
        if geometry.prim_count() == 0 {
            return Ok(out);
        }
        let bvh = build_bvh2(geometry, p.preset);
        let mut c = Collapser {
            bvh: &bvh,
            geometry,
            dp: vec![Choice::default(); bvh.nodes.len()],
            out,
        };
        c.solve(p);
        c.out.root = c.child(0, 0)?;
        out = c.out;
        out.build_time = start.elapsed();
        Ok(out)
    }

    /// Node, block and fill counts, for the docs and the build report.
    pub fn describe(&self) -> String {
        let tris: u64 = self
            .nodes
            .iter()
            .flat_map(|n| n.child.iter())
            .chain([&self.root])
            .filter_map(|c| match c.kind() {
                Kind::Block(_, n) => Some(n as u64),
                _ => None,
            })
            .sum();
        let children: u64 = self.nodes.iter().map(|n| n.count as u64).sum();
        format!(
            "{} nodes ({:.2} children each), {} blocks ({:.2} triangles each), depth {}, built in {:.1} ms",
            self.nodes.len(),
            children as f64 / self.nodes.len().max(1) as f64,
            self.blocks.len(),
            tris as f64 / self.blocks.len().max(1) as f64,
            self.depth,
            self.build_time.as_secs_f64() * 1e3
        )
    }
}
