//! The wide BVH: obvhs builds a binary tree (PLOC + SAH reinsertion, one primitive per leaf), and
//! it is collapsed here into 8-wide nodes with structure-of-arrays child boxes and leaves of up
//! to 8 triangles stored as one SoA block, so one 8-lane sequence tests all children of a node
//! or all triangles of a leaf.
//!
//! Collapse: a bottom-up SAH pass decides which subtrees become leaf blocks (a block test costs
//! about as much as testing all its triangles one by one would cost for one of them, so small
//! subtrees collapse into one block unless their halves are much smaller than the whole); then
//! each wide node starts from a binary node's two children and repeatedly opens the child of
//! largest surface area until it has 8 (the greedy collapse of Wald et al. 2008 / Embree's
//! BVH4/8 builders). Child boxes are the binary nodes' boxes, unchanged.

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
            return Err(Error::Usage(format!(
                "packet backend: {i} nodes exceed 2^30"
            )));
        }
        Ok(Child(i as u32))
    }

    fn block(i: usize, count: usize) -> Result<Child> {
        debug_assert!((1..=BRANCH).contains(&count));
        if i as u64 > INDEX_BITS as u64 {
            return Err(Error::Usage(format!(
                "packet backend: {i} leaf blocks exceed 2^27"
            )));
        }
        Ok(Child(LEAF | ((count as u32 - 1) << COUNT_SHIFT) | i as u32))
    }

    fn sphere(prim: u32) -> Result<Child> {
        if prim >= SPHERE {
            return Err(Error::Usage(format!(
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
    /// Measured on bunny and the dragon (`dibench rays`; docs/tracer.md): obvhs's medium preset
    /// (fast is ~30 % quicker to build and traces a few percent slower), one primitive per
    /// binary leaf so the block decision is ours.
    fn default() -> Self {
        BuildParams {
            preset: BvhBuildParams {
                max_prims_per_leaf: 1,
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

/// Per binary node: triangles below (saturating past a block), spheres below, and whether the
/// subtree becomes one leaf.
#[derive(Clone, Copy, Default)]
struct Info {
    tris: u32,
    spheres: u32,
    leaf: bool,
    cost: f32,
}

struct Collapser<'a> {
    bvh: &'a Bvh2,
    geometry: &'a Geometry,
    info: Vec<Info>,
    out: Wide,
}

fn half_area(b: &Aabb) -> f32 {
    let d = b.max - b.min;
    // Flat boxes (an axis-aligned quad) still cost their traversal.
    (d.x * d.y + d.y * d.z + d.z * d.x).max(0.0)
}

impl Collapser<'_> {
    fn is_sphere(&self, slot: u32) -> bool {
        self.geometry
            .sphere_index(self.bvh.primitive_indices[slot as usize])
            .is_some()
    }

    /// Bottom-up: counts, and the SAH choice between one leaf block and splitting.
    fn annotate(&mut self, p: &BuildParams) {
        let nodes = &self.bvh.nodes;
        // The binary cost of one level: an 8-wide node test stands for three binary levels.
        let bin_cost = p.node_cost / 3.0;
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
            let mut inf = Info::default();
            if n.prim_count > 0 {
                for slot in n.first_index..n.first_index + n.prim_count {
                    if self.is_sphere(slot) {
                        inf.spheres += 1;
                    } else {
                        inf.tris += 1;
                    }
                }
                inf.leaf = true;
                inf.cost =
                    area * p.block_cost * (inf.tris.div_ceil(BRANCH as u32) + inf.spheres) as f32;
            } else {
                let (l, r) = (
                    self.info[n.first_index as usize],
                    self.info[n.first_index as usize + 1],
                );
                inf.tris = (l.tris + r.tris).min(BRANCH as u32 + 1);
                inf.spheres = (l.spheres + r.spheres).min(2);
                let split = area * bin_cost + l.cost + r.cost;
                let fits = inf.spheres == 0 && inf.tris as usize <= BRANCH;
                let as_leaf = area * p.block_cost;
                inf.leaf = fits && as_leaf <= split;
                inf.cost = if inf.leaf { as_leaf } else { split };
            }
            self.info[i] = inf;
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

    /// A leaf child for binary node `i` (its `Info` says it is one).
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
            return Err(Error::Usage(
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

    /// The child for binary node `i`: a leaf, or a new wide node.
    fn child(&mut self, i: usize, depth: usize) -> Result<Child> {
        if self.info[i].leaf {
            return self.leaf(i);
        }
        let nodes = &self.bvh.nodes;
        let mut kids = vec![
            nodes[i].first_index as usize,
            nodes[i].first_index as usize + 1,
        ];
        while kids.len() < BRANCH {
            let open = kids
                .iter()
                .enumerate()
                .filter(|&(_, &k)| !self.info[k].leaf)
                .max_by(|a, b| {
                    half_area(&nodes[*a.1].aabb).total_cmp(&half_area(&nodes[*b.1].aabb))
                })
                .map(|(j, _)| j);
            let Some(j) = open else { break };
            let k = kids.swap_remove(j);
            kids.push(nodes[k].first_index as usize);
            kids.push(nodes[k].first_index as usize + 1);
        }
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
            let (lo, hi) = (nodes[k].aabb.min, nodes[k].aabb.max);
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
            info: vec![Info::default(); bvh.nodes.len()],
            out,
        };
        c.annotate(p);
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
