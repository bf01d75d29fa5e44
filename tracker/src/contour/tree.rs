//! The multiphase distance (MD) tree: a forest of octrees over root blocks, built top-down
//! with the split rule of paper 004 §6.2, and point queries on it (§6.1).

use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseId};
use rayon::prelude::*;

use super::nodes::{Lattice, NodeMap};
use super::sampler::PhaseSampler;

/// `child` of a leaf.
pub(crate) const LEAF: u32 = u32::MAX;

/// Largest root block edge (in cells); see [`block_size`].
const MAX_BLOCK: u64 = 16;

/// Split factor of §6.2: split a cell of edge `h_c` when φ(centre) < `SPLIT_FACTOR`·h_c.
/// The paper takes 3 (after Strain's gradient bound). A cell the interface crosses has its
/// centre within (√3/2)·h_c of it, and the sampled φ is the distance from the centre's
/// departure point, so it is at most L·(√3/2)·h_c for a departure map of Lipschitz constant
/// L ≤ exp(dt·max|∇u|): 2 splits every crossed cell while L ≤ 2.31 (dt·|∇u| ≤ 0.84; `enright`
/// at 64³ steps 0.63, at 128³ 0.31), and cells whose corners' phases differ split anyway.
/// Against 3 it keeps the interface cells and the mesh between phases bit for bit (`enright`,
/// `zalesak`, `vortex4` with the correction off; only the domain-boundary closure is coarser)
/// with a ±4 h finest band instead of ±6 h: `enright` 128³ 99 → 87 s.
const SPLIT_FACTOR: f64 = 2.0;
/// How far (finest cells) a corner's φ is sampled exactly: corners of interface cells lie
/// within a cell's diagonal of the interface, stretched by the step's flow, and only they
/// bound crossings ([`crate::contour::bisect`]); other corners need χ.
const CORNER_REACH_CELLS: f64 = 3.0;
/// Low bits of a sampled point's key that say what it is sampled for.
const USE_BITS: u32 = 6;
const USE_MASK: u64 = (1 << USE_BITS) - 1;

/// One cell of the forest: a box of `edge` unit cells with lower corner `min` (in cells).
/// It is a cube of edge `size` except along a thin axis of the grid (a slab's z), where it
/// spans the whole grid (see [`edges`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cell {
    pub min: [u64; 3],
    /// The cell's level: its edge along every axis the grid is not thinner than.
    pub size: u64,
    /// The edge along each axis, `min(size, dims[a])`.
    pub edge: [u64; 3],
    /// Index of the first of the children (octant order x + 2y + 4z, the octants of the axes
    /// it splits along only; see [`Cell::split_mask`]), or [`LEAF`].
    pub child: u32,
    /// The corners' phase when they all agree.
    pub chi: PhaseId,
    /// The corners' phases differ (only possible for unit leaves once built).
    pub mixed: bool,
    /// Node-store slots of the 8 corners (set once the cell's level is sampled).
    pub slots: [u32; 8],
}

impl Cell {
    /// Lattice coordinates of corner `c` (bits x + 2y + 4z) of this cell.
    #[inline]
    pub fn corner(&self, c: usize) -> [u64; 3] {
        let e = self.edge;
        [
            self.min[0] + e[0] * (c as u64 & 1),
            self.min[1] + e[1] * ((c as u64 >> 1) & 1),
            self.min[2] + e[2] * ((c as u64 >> 2) & 1),
        ]
    }

    /// Lattice coordinates of the centre (a lattice node for size ≥ 2: every edge is then
    /// even, see [`block_size`]).
    #[inline]
    pub fn centre(&self) -> [u64; 3] {
        [0, 1, 2].map(|a| self.min[a] + self.edge[a] / 2)
    }

    /// Bits (x + 2y + 4z) of the axes a split halves: those the cell is as long as its size
    /// along. A cell spanning a thin axis keeps spanning it, so a slab's tree is a quadtree
    /// of columns down to size 2, and an octree below.
    #[inline]
    pub fn split_mask(&self) -> u32 {
        (0..3)
            .filter(|&a| self.edge[a] == self.size)
            .fold(0, |m, a| m | 1 << a)
    }

    /// How many children a split gives: 2 per halved axis.
    #[inline]
    pub fn child_count(&self) -> u32 {
        1 << self.split_mask().count_ones()
    }

    /// Whether corner `k` is a lattice node this cell brings to its level: always for a root
    /// (size `block`); for a child, only if it is not its parent's corner or centre (sampled
    /// a level up) and no sibling in a lower octant has it (the corners shared between
    /// siblings go to the sibling lowest along each axis). So a split's 27 nodes are listed
    /// 18 times instead of 64, and [`MdTree::sample_level`] sorts 2.8× fewer points.
    #[inline]
    fn brings_corner(&self, k: usize, block: u64, dims: [u64; 3]) -> bool {
        if self.size == block {
            return true;
        }
        let mut on_parent_corner = true;
        let mut on_parent_centre = true;
        for (a, &dim) in dims.iter().enumerate() {
            let parent_edge = (2 * self.size).min(dim);
            let parent_min = self.min[a] - self.min[a] % parent_edge;
            let upper = self.min[a] != parent_min;
            let bit = (k >> a) & 1 == 1;
            if upper && !bit {
                return false;
            }
            let q = self.min[a] + if bit { self.edge[a] } else { 0 };
            on_parent_corner &= q == parent_min || q == parent_min + parent_edge;
            on_parent_centre &= q == parent_min + parent_edge / 2;
        }
        !on_parent_corner && !on_parent_centre
    }
}

/// A cell's edges per axis at level `size` in a grid of `dims` cells: `size`, except along
/// an axis thinner than that, which the cell spans.
pub(crate) fn edges(size: u64, dims: [u64; 3]) -> [u64; 3] {
    dims.map(|d| size.min(d))
}

/// The index among a cell's children of the child in octant `k` (bits x + 2y + 4z, zero on
/// the axes outside `mask`): `k`'s bits on the axes of `mask`, packed in axis order, so the
/// children keep octant order.
#[inline]
fn child_rank(k: u32, mask: u32) -> u32 {
    let (mut rank, mut bit) = (0, 0);
    for a in 0..3 {
        if mask >> a & 1 == 1 {
            rank |= (k >> a & 1) << bit;
            bit += 1;
        }
    }
    rank
}

/// Adaptive multiphase distance tree of paper 004 §6: φ and χ sampled at cell corners (and
/// centres of cells of size ≥ 2), refined to unit cells wherever the interface may pass.
///
/// The forest's roots are blocks of edge B, the largest power of two ≤ 16 that divides every
/// `dims[a]` or is divided by it, so any grid is tiled exactly. An axis thinner than B (a
/// slab's two cells in z: a 256×256×2 slab has B = 16) is spanned whole by every cell of
/// size ≥ its thickness: the tree coarsens in the slab's plane as a 2D quadtree would.
#[derive(Clone, Debug)]
pub struct MdTree {
    pub(crate) lattice: Lattice,
    pub(crate) block: u64,
    pub(crate) roots: [u64; 3],
    pub(crate) cells: Vec<Cell>,
    /// φ, χ as sampled while building (φ drives the contour's bisection brackets and is what
    /// [`MdTree::sample`] interpolates: exact near the interface, a lower bound far from it).
    pub(crate) nodes: NodeMap,
    /// Unit leaves whose corners' χ differ, sorted by lattice id of their lower corner.
    pub(crate) interface: Vec<u32>,
}

/// Largest power of two b ≤ 16 such that each of `dims` (all positive) is a multiple of b,
/// or a power of two ≥ 2 below b (a thin axis: the cells span it, and their centres stay
/// lattice nodes), and at least one is a multiple (so every split halves some axis).
fn block_size(dims: [u64; 3]) -> u64 {
    let mut b = MAX_BLOCK;
    let tiles = |d: u64, b: u64| d.is_multiple_of(b) || (2..b).contains(&d) && b.is_multiple_of(d);
    while b > 1 && !(dims.iter().all(|&d| tiles(d, b)) && dims.iter().any(|&d| d >= b)) {
        b /= 2;
    }
    b
}

impl MdTree {
    /// Top-down build (§6.2): split a cell if φ(centre) < [`SPLIT_FACTOR`]·h_cell or its
    /// corner χ differ;
    /// only the finest level meets the interface. New values are evaluated once per node,
    /// level by level, in parallel over a sorted, deduplicated list of the points that level
    /// needs.
    pub fn build(grid: &GridSpec, sampler: &dyn PhaseSampler) -> MdTree {
        let lattice = Lattice::new(grid);
        let mut tree = MdTree {
            lattice,
            block: 1,
            roots: [0; 3],
            cells: Vec::new(),
            nodes: NodeMap::default(),
            interface: Vec::new(),
        };
        if lattice.dims.contains(&0) {
            return tree;
        }
        let b = block_size(lattice.dims);
        tree.block = b;
        tree.roots = lattice.dims.map(|d| d.div_ceil(b));
        for k in 0..tree.roots[2] {
            for j in 0..tree.roots[1] {
                for i in 0..tree.roots[0] {
                    tree.cells.push(Cell {
                        min: [i * b, j * b, k * b],
                        size: b,
                        edge: edges(b, lattice.dims),
                        child: LEAF,
                        chi: 0,
                        mixed: false,
                        slots: [0; 8],
                    });
                }
            }
        }
        tree.refine_from((0..tree.cells.len() as u32).collect(), sampler);
        tree.conform(sampler);
        let mut interface: Vec<(u64, u32)> = tree
            .cells
            .iter()
            .enumerate()
            .filter(|(_, c)| c.mixed && c.child == LEAF)
            .map(|(i, c)| (lattice.id(c.min), i as u32))
            .collect();
        interface.sort_unstable();
        tree.interface = interface.into_iter().map(|(_, i)| i).collect();
        tree
    }

    /// Evaluate the sampler at the corners (and centres, size ≥ 2) of `frontier` not yet stored.
    ///
    /// Each point is sampled only as far as its uses need ([`PhaseSampler::sample_near`]): a
    /// centre of a cell of size s up to the split threshold [`SPLIT_FACTOR`]·h·s; a corner up to
    /// [`CORNER_REACH_CELLS`] cells, beyond which only its χ is read (a far corner never
    /// bounds a crossing, and corners are never centres later: corners of size-s cells lie on
    /// multiples of s, centres of smaller cells on odd multiples of half their size).
    /// `frontier` holds roots or whole sibling groups, each child's parent already sampled
    /// ([`Cell::brings_corner`]).
    fn sample_level(&mut self, frontier: &[u32], sampler: &dyn PhaseSampler) {
        let lat = self.lattice;
        let (cells, block) = (&self.cells, self.block);
        // Node id above, the use's size code below: 0 for a corner, log2(s) + 1 for a centre.
        let mut pts: Vec<u64> = frontier
            .par_iter()
            .flat_map_iter(|&c| {
                let cell = cells[c as usize];
                let centre = (cell.size >= 2).then(|| {
                    lat.id(cell.centre()) << USE_BITS | u64::from(cell.size.trailing_zeros() + 1)
                });
                (0..8)
                    .filter(move |&k| cell.brings_corner(k, block, lat.dims))
                    .map(move |k| lat.id(cell.corner(k)) << USE_BITS)
                    .chain(centre)
            })
            .collect();
        pts.par_sort_unstable();
        // Sorted, so each node's widest use comes last.
        pts.dedup_by(|next, kept| {
            let same = *next >> USE_BITS == *kept >> USE_BITS;
            if same {
                *kept = *next;
            }
            same
        });
        let nodes = &self.nodes;
        pts.retain(|&p| nodes.get(p >> USE_BITS).is_none());
        let h = lat.h;
        let vals: Vec<(f64, PhaseId)> = pts
            .par_iter()
            .map(|&p| {
                let reach = match p & USE_MASK {
                    0 => CORNER_REACH_CELLS * h,
                    code => SPLIT_FACTOR * h * (1u64 << (code - 1)) as f64,
                };
                sampler.sample_near(lat.pos(p >> USE_BITS), reach)
            })
            .collect();
        self.nodes.reserve(pts.len());
        for (p, (phi, chi)) in pts.into_iter().zip(vals) {
            self.nodes.insert(p >> USE_BITS, phi, chi);
        }
    }

    /// Sample and refine level by level, starting with the cells `frontier`.
    fn refine_from(&mut self, mut frontier: Vec<u32>, sampler: &dyn PhaseSampler) {
        while !frontier.is_empty() {
            self.sample_level(&frontier, sampler);
            frontier = self.refine_level(&frontier);
        }
    }

    /// Give leaf `c` its children (8, or 4 in a slab's plane; octant order); returns their
    /// indices.
    fn split(&mut self, c: u32) -> std::ops::Range<u32> {
        let first = self.cells.len() as u32;
        let parent = self.cells[c as usize];
        self.cells[c as usize].child = first;
        let half = parent.size / 2;
        let mask = parent.split_mask();
        for k in (0..8u32).filter(|k| k & !mask == 0) {
            self.cells.push(Cell {
                min: [0, 1, 2].map(|a| parent.min[a] + half * u64::from(k >> a & 1)),
                size: half,
                edge: edges(half, self.lattice.dims),
                child: LEAF,
                chi: 0,
                mixed: false,
                slots: [0; 8],
            });
        }
        first..first + parent.child_count()
    }

    /// Safety net for samplers whose φ over-estimates the distance (a semi-Lagrangian φ is
    /// only approximately a distance): the contour is watertight only if every face or edge
    /// of an interface cell whose corners' χ differ is shared with unit cells, never with a
    /// coarse leaf (which the stencils skip). With a lower-bound φ the split rule guarantees
    /// this (a coarse leaf lies ≥ 2·s·h − (√3/2)·s·h from the interface) and this pass finds
    /// nothing; otherwise it splits the offending coarse leaves until it holds.
    fn conform(&mut self, sampler: &dyn PhaseSampler) {
        loop {
            let mut offending: Vec<u32> = self
                .cells
                .par_iter()
                .filter(|c| c.child == LEAF && c.mixed && c.size == 1)
                .flat_map_iter(|c| self.coarse_neighbours(c))
                .collect();
            offending.par_sort_unstable();
            offending.dedup();
            if offending.is_empty() {
                return;
            }
            let frontier: Vec<u32> = offending.into_iter().flat_map(|c| self.split(c)).collect();
            self.refine_from(frontier, sampler);
        }
    }

    /// Coarse leaves sharing a face or an edge with unit cell `c` across which χ changes.
    pub(crate) fn coarse_neighbours(&self, c: &Cell) -> Vec<u32> {
        let chi = c.slots.map(|s| self.nodes.chi[s as usize]);
        let mut out = Vec::new();
        for d in 0..27usize {
            let off = [d % 3, (d / 3) % 3, d / 9].map(|o| o as i64 - 1);
            let zeros = off.iter().filter(|&&o| o == 0).count();
            if zeros == 3 || zeros == 0 {
                continue;
            }
            let mut n = [0u64; 3];
            let mut inside = true;
            for a in 0..3 {
                let q = c.min[a] as i64 + off[a];
                inside &= q >= 0 && (q as u64) < self.lattice.dims[a];
                n[a] = q.max(0) as u64;
            }
            if !inside {
                continue;
            }
            // Corners of `c` on the shared face / edge: bit a is 1 towards +a, 0 towards −a.
            let shared = (0..8)
                .filter(|&k| (0..3).all(|a| off[a] == 0 || ((k >> a) & 1 == 1) == (off[a] > 0)));
            let mut labels = shared.map(|k| chi[k]);
            let first = labels.next();
            if labels.all(|l| Some(l) == first) {
                continue;
            }
            let centre = DVec3::new(n[0] as f64 + 0.5, n[1] as f64 + 0.5, n[2] as f64 + 0.5);
            if let Some(leaf) = self.leaf_at(centre) {
                if self.cells[leaf as usize].size > 1 {
                    out.push(leaf);
                }
            }
        }
        out
    }

    /// Apply the split rule to `frontier`; returns the children created (the next level).
    fn refine_level(&mut self, frontier: &[u32]) -> Vec<u32> {
        let lat = self.lattice;
        let h = lat.h;
        let (cells, nodes) = (&self.cells, &self.nodes);
        let decisions: Vec<(bool, bool, [u32; 8])> = frontier
            .par_iter()
            .map(|&c| {
                let cell = cells[c as usize];
                let slots: [u32; 8] = std::array::from_fn(|k| {
                    nodes.get(lat.id(cell.corner(k))).map_or(0, |s| s as u32)
                });
                let chi0 = nodes.chi[slots[0] as usize];
                let mixed = slots.iter().any(|&s| nodes.chi[s as usize] != chi0);
                let split = cell.size >= 2
                    && (mixed || {
                        let centre = lat.id(cell.centre());
                        let phi = nodes.value(centre).map_or(0.0, |v| v.0);
                        phi < SPLIT_FACTOR * h * cell.size as f64
                    });
                (split, mixed, slots)
            })
            .collect();
        let mut next = Vec::new();
        for (&c, (split, mixed, slots)) in frontier.iter().zip(decisions) {
            let cell = &mut self.cells[c as usize];
            cell.mixed = mixed;
            cell.chi = self.nodes.chi[slots[0] as usize];
            cell.slots = slots;
            if !split {
                continue;
            }
            next.extend(self.split(c));
        }
        next
    }

    /// All tree cells, internal and leaves (paper 004 Table 1 "Cells").
    pub fn cell_count(&self) -> usize {
        self.cells.len()
    }

    /// Finest cells whose corners' χ differ (paper 004 Table 1 "Intersect Cells").
    pub fn interface_cell_count(&self) -> usize {
        self.interface.len()
    }

    /// Number of lattice nodes where φ, χ were evaluated (one sampler call each).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The leaf containing lattice-unit point `u` (already clamped to the box).
    pub(crate) fn leaf_at(&self, u: DVec3) -> Option<u32> {
        if self.cells.is_empty() {
            return None;
        }
        let b = self.block as f64;
        let r = [0, 1, 2].map(|a| ((u[a] / b).floor().max(0.0) as u64).min(self.roots[a] - 1));
        let mut c = (r[0] + self.roots[0] * (r[1] + self.roots[1] * r[2])) as u32;
        loop {
            let cell = self.cells[c as usize];
            if cell.child == LEAF {
                return Some(c);
            }
            let half = (cell.size / 2) as f64;
            let mask = cell.split_mask();
            let oct = (0..3).fold(0u32, |o, a| {
                o | (((u[a] >= cell.min[a] as f64 + half) as u32) << a)
            });
            c = cell.child + child_rank(oct & mask, mask);
        }
    }

    /// φ, χ at any point from the tree (§6.1): `Some((interpolated φ, χ))` where the containing
    /// leaf has uniform χ, `None` in interface cells (the caller then queries the mesh exactly).
    /// Points outside the grid box are clamped to it.
    pub fn sample(&self, x: DVec3) -> Option<(f64, PhaseId)> {
        let lat = &self.lattice;
        let hi = DVec3::new(lat.dims[0] as f64, lat.dims[1] as f64, lat.dims[2] as f64);
        let u = ((x - lat.origin) / lat.h).clamp(DVec3::ZERO, hi);
        let c = self.leaf_at(u)?;
        let cell = self.cells[c as usize];
        if cell.mixed {
            return None;
        }
        let [ex, ey, ez] = cell.edge.map(|e| e as f64);
        let t = (u - DVec3::new(cell.min[0] as f64, cell.min[1] as f64, cell.min[2] as f64))
            / DVec3::new(ex, ey, ez);
        let mut phi = 0.0;
        for k in 0..8 {
            let w = (0..3).fold(1.0, |w, a| {
                w * if (k >> a) & 1 == 1 { t[a] } else { 1.0 - t[a] }
            });
            phi += w * self.nodes.phi[cell.slots[k] as usize];
        }
        Some((phi, cell.chi))
    }
}
