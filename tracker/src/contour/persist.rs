//! An exact byte image of an [`MdTree`] (every f64 as its bits), so a checkpointed tracker
//! answers φ, χ off its tree after a restart exactly as before: the tree was built from the
//! previous step's departure points and cannot be rebuilt from the mesh alone.

use glam::DVec3;
use thiserror::Error;

use super::nodes::{Lattice, NodeMap};
use super::tree::{edges, Cell, MdTree, LEAF};

/// Why bytes are not a tree image.
#[derive(Debug, Error, PartialEq)]
pub enum TreeDecodeError {
    /// The bytes end early (or a count is larger than the bytes left).
    #[error("tree image truncated")]
    Truncated,
    /// The bytes decode but do not form a tree (an index out of range, bytes left over).
    #[error("tree image inconsistent: {0}")]
    Inconsistent(String),
}

impl MdTree {
    /// The tree as little-endian bytes; [`MdTree::from_bytes`] reads them back bit for bit.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Vec::new();
        let lat = &self.lattice;
        for v in [lat.origin.x, lat.origin.y, lat.origin.z, lat.h] {
            w.extend_from_slice(&v.to_bits().to_le_bytes());
        }
        let words = lat.dims.iter().chain(&lat.n).chain([&self.block]);
        words
            .chain(&self.roots)
            .for_each(|v| w.extend_from_slice(&v.to_le_bytes()));
        w.extend_from_slice(&(self.cells.len() as u64).to_le_bytes());
        for c in &self.cells {
            for v in c.min.iter().chain([&c.size]) {
                w.extend_from_slice(&v.to_le_bytes());
            }
            w.extend_from_slice(&c.child.to_le_bytes());
            w.extend_from_slice(&c.chi.to_le_bytes());
            w.push(u8::from(c.mixed));
            c.slots
                .iter()
                .for_each(|s| w.extend_from_slice(&s.to_le_bytes()));
        }
        let nodes = &self.nodes;
        w.extend_from_slice(&(nodes.len() as u64).to_le_bytes());
        nodes
            .keys
            .iter()
            .for_each(|k| w.extend_from_slice(&k.to_le_bytes()));
        nodes
            .phi
            .iter()
            .for_each(|p| w.extend_from_slice(&p.to_bits().to_le_bytes()));
        nodes
            .chi
            .iter()
            .for_each(|c| w.extend_from_slice(&c.to_le_bytes()));
        w.extend_from_slice(&(self.interface.len() as u64).to_le_bytes());
        self.interface
            .iter()
            .for_each(|c| w.extend_from_slice(&c.to_le_bytes()));
        w
    }

    /// Reads [`MdTree::to_bytes`]; checks every index the queries follow, so a damaged
    /// image is an error, never a panic later.
    pub fn from_bytes(bytes: &[u8]) -> Result<MdTree, TreeDecodeError> {
        let mut r = Reader(bytes);
        let origin = DVec3::new(r.f64()?, r.f64()?, r.f64()?);
        let lattice = Lattice {
            origin,
            h: r.f64()?,
            dims: [r.u64()?, r.u64()?, r.u64()?],
            n: [r.u64()?, r.u64()?, r.u64()?],
        };
        let block = r.u64()?;
        let roots = [r.u64()?, r.u64()?, r.u64()?];
        let n_cells = r.count(8 * 4 + 4 + 2 + 1 + 8 * 4)?;
        let mut cells = Vec::with_capacity(n_cells);
        for _ in 0..n_cells {
            let (min, size) = ([r.u64()?, r.u64()?, r.u64()?], r.u64()?);
            let (child, chi) = (r.u32()?, u16::from_le_bytes(r.take()?));
            let mixed = r.take::<1>()?[0] != 0;
            let mut slots = [0; 8];
            for s in &mut slots {
                *s = r.u32()?;
            }
            cells.push(Cell {
                min,
                size,
                edge: edges(size, lattice.dims),
                child,
                chi,
                mixed,
                slots,
            });
        }
        let n_nodes = r.count(8 + 8 + 2)?;
        let keys = (0..n_nodes)
            .map(|_| r.u64())
            .collect::<Result<Vec<_>, _>>()?;
        let phi = (0..n_nodes)
            .map(|_| r.f64())
            .collect::<Result<Vec<_>, _>>()?;
        let mut nodes = NodeMap::default();
        nodes.reserve(n_nodes);
        for (&key, &phi) in keys.iter().zip(&phi) {
            nodes.insert(key, phi, u16::from_le_bytes(r.take()?));
        }
        let n_interface = r.count(4)?;
        let interface = (0..n_interface)
            .map(|_| r.u32())
            .collect::<Result<Vec<_>, _>>()?;
        let bad = |what: String| Err(TreeDecodeError::Inconsistent(what));
        if !r.0.is_empty() {
            return bad(format!("{} bytes left over", r.0.len()));
        }
        let n_roots = roots.iter().try_fold(1u64, |p, &n| p.checked_mul(n));
        if !cells.is_empty() && n_roots.is_none_or(|n| n == 0 || n > cells.len() as u64) {
            return bad(format!("{roots:?} root blocks for {} cells", cells.len()));
        }
        if block == 0 || (lattice.dims.contains(&0) != cells.is_empty()) {
            return bad("block size or lattice".into());
        }
        for (i, c) in cells.iter().enumerate() {
            let children_fit =
                c.child == LEAF || (c.child as usize) + c.child_count() as usize <= cells.len();
            let slots_fit = c.child != LEAF || c.slots.iter().all(|&s| (s as usize) < nodes.len());
            if !children_fit || !slots_fit {
                return bad(format!("cell {i} points outside the tree"));
            }
        }
        if interface.iter().any(|&c| c as usize >= cells.len()) {
            return bad("interface cell out of range".into());
        }
        Ok(MdTree {
            lattice,
            block,
            roots,
            cells,
            nodes,
            interface,
        })
    }
}

/// Little-endian reads that fail instead of running past the end.
struct Reader<'a>(&'a [u8]);

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> Result<[u8; N], TreeDecodeError> {
        let (head, tail) = self
            .0
            .split_first_chunk::<N>()
            .ok_or(TreeDecodeError::Truncated)?;
        self.0 = tail;
        Ok(*head)
    }

    fn u64(&mut self) -> Result<u64, TreeDecodeError> {
        self.take().map(u64::from_le_bytes)
    }

    fn f64(&mut self) -> Result<f64, TreeDecodeError> {
        self.u64().map(f64::from_bits)
    }

    fn u32(&mut self) -> Result<u32, TreeDecodeError> {
        self.take().map(u32::from_le_bytes)
    }

    /// A count of records of `size` bytes each, refused when the bytes left cannot hold them
    /// (so a damaged count never asks for a huge allocation).
    fn count(&mut self, size: usize) -> Result<usize, TreeDecodeError> {
        let n = usize::try_from(self.u64()?).map_err(|_| TreeDecodeError::Truncated)?;
        if n > self.0.len() / size {
            return Err(TreeDecodeError::Truncated);
        }
        Ok(n)
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use polyphase_grid::{GridSpec, PhaseId};

    use super::*;

    /// A ball of phase 1 in phase 0, built and contoured like a tracker's tree.
    fn ball_tree() -> MdTree {
        let grid = GridSpec {
            origin: DVec3::ZERO,
            h: 1.0 / 16.0,
            dims: [16, 16, 16],
        };
        let c = DVec3::splat(0.5);
        let sampler = |x: DVec3| -> (f64, PhaseId) {
            let d = (x - c).length() - 0.3;
            (d.abs(), PhaseId::from(d < 0.0))
        };
        let tree = MdTree::build(&grid, &sampler);
        tree.contour(&sampler);
        tree
    }

    #[test]
    fn image_round_trip_answers_every_sample_alike() {
        let tree = ball_tree();
        let back = MdTree::from_bytes(&tree.to_bytes()).unwrap();
        assert_eq!(back.to_bytes(), tree.to_bytes());
        let mut answered = [0; 2];
        for i in 0..2000 {
            // Points on a scrambled lattice of the unit box, interface and far cells alike.
            let f = |k: u64| ((i as u64 * k) % 1009) as f64 / 1009.0;
            let x = DVec3::new(f(37), f(101), f(367));
            let (a, b) = (tree.sample(x), back.sample(x));
            assert_eq!(
                a.map(|(p, c)| (p.to_bits(), c)),
                b.map(|(p, c)| (p.to_bits(), c))
            );
            answered[usize::from(a.is_some())] += 1;
        }
        // Both the tree's uniform leaves and its interface cells (None: "ask the mesh") were hit.
        assert!(answered.iter().all(|&n| n > 0), "{answered:?}");
    }

    #[test]
    fn slab_image_round_trip_keeps_the_columns() {
        // Cells spanning a slab's thickness get their edges back from the lattice.
        let grid = GridSpec {
            origin: DVec3::ZERO,
            h: 1.0 / 64.0,
            dims: [64, 32, 2],
        };
        let sampler = |x: DVec3| -> (f64, PhaseId) {
            let d = (x - DVec3::new(0.5, 0.25, x.z)).length() - 0.15;
            (d.abs(), PhaseId::from(d < 0.0))
        };
        let tree = MdTree::build(&grid, &sampler);
        assert!(tree.cells.iter().any(|c| c.size > 2));
        let back = MdTree::from_bytes(&tree.to_bytes()).unwrap();
        assert_eq!(back.to_bytes(), tree.to_bytes());
        assert!(back
            .cells
            .iter()
            .zip(&tree.cells)
            .all(|(a, b)| a.edge == b.edge));
        for i in 0..1000 {
            let f = |k: u64| ((i as u64 * k) % 1009) as f64 / 1009.0;
            let x = DVec3::new(f(37), 0.5 * f(101), 2.0 * grid.h * f(367));
            let (a, b) = (tree.sample(x), back.sample(x));
            assert_eq!(
                a.map(|(p, c)| (p.to_bits(), c)),
                b.map(|(p, c)| (p.to_bits(), c))
            );
        }
    }

    #[test]
    fn damaged_images_are_errors() {
        let bytes = ball_tree().to_bytes();
        for cut in [0, 7, 100, bytes.len() / 2, bytes.len() - 1] {
            assert!(MdTree::from_bytes(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        let mut long = bytes.clone();
        long.push(0);
        assert!(MdTree::from_bytes(&long).is_err());
    }
}
