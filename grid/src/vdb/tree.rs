//! The sparse tree of OpenVDB's standard configuration (root → 32³ internal → 16³ internal
//! → 8³ leaf, "5_4_3") built from a dense cell array, and its two serialised parts:
//! topology (node masks) and buffers (leaf values).
//!
//! A voxel is active when it lies inside the grid and its value differs (bit for bit)
//! from the background; inactive voxels read back as the background, so every cell value
//! survives exactly. Leaves without an active voxel are not written.

use super::stream::Out;
use super::{Compression, VdbError};

/// log2 of a leaf's edge in voxels (8).
const LEAF_LOG2: u32 = 3;
/// log2 of the lower internal node's edge in voxels (16 leaves × 8 = 128).
const LOWER_LOG2: u32 = 7;
/// log2 of the upper internal node's edge in voxels (32 lower nodes × 128 = 4096).
const UPPER_LOG2: u32 = 12;
/// Words of a leaf mask (512 bits).
const LEAF_WORDS: usize = 8;
/// Words of a lower internal node's mask (16³ bits).
const LOWER_WORDS: usize = 64;
/// Words of an upper internal node's mask (32³ bits).
const UPPER_WORDS: usize = 512;

/// Per-node compression indicator: every inactive value equals the background, so only
/// active values are stored (OpenVDB io/Compression.h, `NO_MASK_OR_INACTIVE_VALS`).
const NO_MASK_OR_INACTIVE_VALS: u8 = 0;

/// A value type OpenVDB knows by a tree type name.
pub(super) trait Voxel: Copy {
    /// Tree type name of the standard 5_4_3 configuration for this value type.
    const TREE_TYPE: &'static str;
    /// Bitwise equality, so that -0.0 and NaN payloads are kept exactly.
    fn same(&self, other: &Self) -> bool;
    /// Appends the value's little-endian bytes.
    fn put(&self, out: &mut Vec<u8>);
}

impl Voxel for f32 {
    const TREE_TYPE: &'static str = "Tree_float_5_4_3";
    fn same(&self, other: &Self) -> bool {
        self.to_bits() == other.to_bits()
    }
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
}

impl Voxel for [f32; 3] {
    const TREE_TYPE: &'static str = "Tree_vec3s_5_4_3";
    fn same(&self, other: &Self) -> bool {
        self.iter().zip(other).all(|(a, b)| a.same(b))
    }
    fn put(&self, out: &mut Vec<u8>) {
        for c in self {
            c.put(out);
        }
    }
}

/// One 8³ leaf holding at least one active voxel.
struct Leaf {
    /// Index-space origin (a multiple of 8 on each axis).
    origin: [u32; 3],
    /// Active voxels; bit `x << 6 | y << 3 | z` (local coordinates, z fastest).
    mask: [u64; LEAF_WORDS],
    /// Serialised active values in mask order.
    active: Vec<u8>,
}

/// The leaves of a grid in the order OpenVDB writes them (depth first, children of
/// each node by ascending table offset, root children by ascending origin).
pub(super) struct Tree {
    leaves: Vec<Leaf>,
    /// Serialised background value.
    background: Vec<u8>,
    /// Index-space bounding box (inclusive) of the active voxels, if any.
    pub active_bbox: Option<([u32; 3], [u32; 3])>,
    /// Number of active voxels.
    pub active_count: u64,
}

impl Tree {
    /// Builds the tree of `values` (cell `i + nx*(j + ny*k)` is voxel (i, j, k)).
    pub fn build<T: Voxel>(dims: [usize; 3], values: &[T], background: T) -> Self {
        let [nx, ny, nz] = dims;
        let leaf = 1usize << LEAF_LOG2;
        let mut leaves = Vec::new();
        let mut active_bbox: Option<([u32; 3], [u32; 3])> = None;
        let mut active_count = 0;
        for ox in (0..nx).step_by(leaf) {
            for oy in (0..ny).step_by(leaf) {
                for oz in (0..nz).step_by(leaf) {
                    let mut mask = [0u64; LEAF_WORDS];
                    let mut active = Vec::with_capacity(512 * std::mem::size_of::<T>());
                    for x in ox..(ox + leaf).min(nx) {
                        for y in oy..(oy + leaf).min(ny) {
                            for z in oz..(oz + leaf).min(nz) {
                                let v = values[x + nx * (y + ny * z)];
                                if v.same(&background) {
                                    continue;
                                }
                                let n = (x - ox) << 6 | (y - oy) << 3 | (z - oz);
                                mask[n / 64] |= 1 << (n % 64);
                                v.put(&mut active);
                                active_count += 1;
                                // The caller checked that every dimension fits an i32.
                                let p = [x as u32, y as u32, z as u32];
                                let (lo, hi) = active_bbox.get_or_insert((p, p));
                                for a in 0..3 {
                                    lo[a] = lo[a].min(p[a]);
                                    hi[a] = hi[a].max(p[a]);
                                }
                            }
                        }
                    }
                    if !active.is_empty() {
                        let origin = [ox as u32, oy as u32, oz as u32];
                        leaves.push(Leaf {
                            origin,
                            mask,
                            active,
                        });
                    }
                }
            }
        }
        leaves.sort_by_key(|l| order_key(l.origin));
        let mut bg = Vec::new();
        background.put(&mut bg);
        Tree {
            leaves,
            background: bg,
            active_bbox,
            active_count,
        }
    }

    /// Writes the topology: root header, then each node's child and value masks and
    /// (empty) tile values, depth first; leaves contribute their value masks.
    pub fn write_topology(&self, out: &mut Out, compression: Compression) -> Result<(), VdbError> {
        out.u32(1); // buffer count: one value buffer per leaf
        out.raw(&self.background);
        let uppers = runs(&self.leaves, UPPER_LOG2);
        out.u32(0); // root tiles
        out.u32(uppers.len() as u32); // root children
        for upper in uppers {
            let origin = upper[0].origin.map(|c| c >> UPPER_LOG2 << UPPER_LOG2);
            for c in origin {
                out.i32(c as i32);
            }
            let lowers = runs(upper, LOWER_LOG2);
            let mut children = vec![0u64; UPPER_WORDS];
            for lower in &lowers {
                set_bit(
                    &mut children,
                    offset(lower[0].origin, UPPER_LOG2, LOWER_LOG2),
                );
            }
            write_internal(out, &children, compression)?;
            for lower in lowers {
                let mut children = vec![0u64; LOWER_WORDS];
                for leaf in lower {
                    set_bit(&mut children, offset(leaf.origin, LOWER_LOG2, LEAF_LOG2));
                }
                write_internal(out, &children, compression)?;
                for leaf in lower {
                    out.mask(&leaf.mask);
                }
            }
        }
        Ok(())
    }

    /// Writes the buffers: for each leaf in topology order its value mask, the
    /// compression indicator and its active values.
    pub fn write_buffers(&self, out: &mut Out, compression: Compression) -> Result<(), VdbError> {
        for leaf in &self.leaves {
            out.mask(&leaf.mask);
            out.u8(NO_MASK_OR_INACTIVE_VALS);
            out.values(&leaf.active, compression)?;
        }
        Ok(())
    }
}

/// An internal node without tiles: child mask, an all-off value mask, and its tile
/// values, of which none are active and all inactive ones are the background.
fn write_internal(
    out: &mut Out,
    children: &[u64],
    compression: Compression,
) -> Result<(), VdbError> {
    out.mask(children);
    out.mask(&vec![0u64; children.len()]);
    out.u8(NO_MASK_OR_INACTIVE_VALS);
    out.values(&[], compression)
}

/// Sort key giving OpenVDB's write order of leaves: by upper node origin (x, y, z),
/// then lower node, then leaf; within a node the table offset runs x slowest, z fastest.
fn order_key(o: [u32; 3]) -> [u32; 9] {
    let [x, y, z] = o;
    [
        x >> UPPER_LOG2,
        y >> UPPER_LOG2,
        z >> UPPER_LOG2,
        x >> LOWER_LOG2,
        y >> LOWER_LOG2,
        z >> LOWER_LOG2,
        x >> LEAF_LOG2,
        y >> LEAF_LOG2,
        z >> LEAF_LOG2,
    ]
}

/// Splits sorted leaves into runs that share the node of edge `2^log2` voxels.
fn runs(leaves: &[Leaf], log2: u32) -> Vec<&[Leaf]> {
    let node = |l: &Leaf| l.origin.map(|c| c >> log2);
    let mut out = Vec::new();
    let mut start = 0;
    for i in 1..=leaves.len() {
        if i == leaves.len() || node(&leaves[i]) != node(&leaves[start]) {
            out.push(&leaves[start..i]);
            start = i;
        }
    }
    out
}

/// Table offset of the child containing `origin` in a node of edge `2^node_log2` whose
/// children have edge `2^child_log2`: x slowest, z fastest.
fn offset(origin: [u32; 3], node_log2: u32, child_log2: u32) -> usize {
    let bits = node_log2 - child_log2;
    let local = origin.map(|c| ((c & ((1 << node_log2) - 1)) >> child_log2) as usize);
    local[0] << (2 * bits) | local[1] << bits | local[2]
}

fn set_bit(words: &mut [u64], n: usize) {
    words[n / 64] |= 1 << (n % 64);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inactive_voxels_are_background_and_empty_leaves_dropped() {
        // 10×3×2 grid: two leaves along x; the second holds only background.
        let dims = [10, 3, 2];
        let mut values = vec![0.0f32; 60];
        values[0] = 1.0;
        values[5] = -0.0; // differs bitwise from +0.0, so active
        let tree = Tree::build(dims, &values, 0.0);
        assert_eq!(tree.leaves.len(), 1);
        assert_eq!(tree.active_count, 2);
        let ones: u32 = tree.leaves[0].mask.iter().map(|w| w.count_ones()).sum();
        assert_eq!(ones, 2);
        assert_eq!(tree.active_bbox, Some(([0, 0, 0], [5, 0, 0])));
        // voxel (5,0,0): local offset 5 << 6
        assert_eq!(tree.leaves[0].mask[5], 1);
        assert_eq!(tree.leaves[0].mask[0], 1);
    }

    #[test]
    fn leaves_follow_node_order_not_raster_order() {
        // Leaves at y = 0 and y = 128 under x = 0, and y = 0 under x = 8: the node
        // at y = 128 is a different lower node, so it comes after both y = 0 leaves.
        let a = order_key([0, 0, 0]);
        let b = order_key([8, 0, 0]);
        let c = order_key([0, 128, 0]);
        assert!(a < b && b < c);
        assert_eq!(offset([8, 0, 0], LOWER_LOG2, LEAF_LOG2), 256);
        assert_eq!(offset([0, 0, 136], LOWER_LOG2, LEAF_LOG2), 1);
        assert_eq!(offset([128, 0, 0], UPPER_LOG2, LOWER_LOG2), 1024);
    }
}
