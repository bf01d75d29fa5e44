//! The unit node lattice of the tracker grid and the sparse store of φ, χ at its nodes.
//!
//! Every point the MD tree samples (cell corners, and centres of cells of size ≥ 2) is a node
//! of the unit lattice, so one map keyed by the linear node index serves all levels
//! (paper 004 §6: "ϕ and χ are sampled on the corner vertices and the center of the cell").
//! The map is std's `HashMap` with a folded-multiply hash of the node id. Measured on the
//! 263k nodes of a 256³ shell band: 15 ns per lookup, like a hand-written linear-probing
//! table (16 ns, with slower inserts), 4× faster than the default SipHash. Nothing iterates
//! the map: values live in insertion order, which is deterministic.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseId};

/// Node indexing of a [`GridSpec`]: node (i, j, k), 0 ≤ i ≤ dims[0], has id
/// `i + (dims[0]+1)·(j + (dims[1]+1)·k)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Lattice {
    pub origin: DVec3,
    pub h: f64,
    /// Cells per axis.
    pub dims: [u64; 3],
    /// Nodes per axis (`dims + 1`).
    pub n: [u64; 3],
}

impl Lattice {
    pub fn new(grid: &GridSpec) -> Self {
        let dims = grid.dims.map(|d| d as u64);
        Lattice {
            origin: grid.origin,
            h: grid.h,
            dims,
            n: dims.map(|d| d + 1),
        }
    }

    #[inline]
    pub fn id(&self, p: [u64; 3]) -> u64 {
        p[0] + self.n[0] * (p[1] + self.n[1] * p[2])
    }

    #[inline]
    pub fn ijk(&self, id: u64) -> [u64; 3] {
        let i = id % self.n[0];
        let r = id / self.n[0];
        [i, r % self.n[1], r / self.n[1]]
    }

    /// World position of lattice point `p` (integer coordinates in cells).
    #[inline]
    pub fn pos_ijk(&self, p: [u64; 3]) -> DVec3 {
        self.origin + DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) * self.h
    }

    #[inline]
    pub fn pos(&self, id: u64) -> DVec3 {
        self.pos_ijk(self.ijk(id))
    }
}

/// Folded 128-bit multiply of a `u64` key: every output bit depends on every input bit.
#[derive(Default)]
pub(crate) struct FoldHasher(u64);

impl Hasher for FoldHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(self.0 ^ u64::from(b));
        }
    }

    fn write_u64(&mut self, key: u64) {
        let p = (key as u128).wrapping_mul(0x9E37_79B9_7F4A_7C15_u128);
        self.0 = (p >> 64) as u64 ^ p as u64;
    }
}

/// Sparse φ, χ at lattice nodes: an index (`slot`) per node in insertion order.
#[derive(Clone, Debug, Default)]
pub(crate) struct NodeMap {
    index: HashMap<u64, u32, BuildHasherDefault<FoldHasher>>,
    pub keys: Vec<u64>,
    pub phi: Vec<f64>,
    pub chi: Vec<PhaseId>,
}

impl NodeMap {
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// Slot of node `key`, if stored.
    #[inline]
    pub fn get(&self, key: u64) -> Option<usize> {
        self.index.get(&key).map(|&s| s as usize)
    }

    /// φ, χ of node `key`, if stored.
    #[inline]
    pub fn value(&self, key: u64) -> Option<(f64, PhaseId)> {
        self.get(key).map(|s| (self.phi[s], self.chi[s]))
    }

    /// Make room for `n` more nodes.
    pub fn reserve(&mut self, n: usize) {
        self.index.reserve(n);
        self.keys.reserve(n);
        self.phi.reserve(n);
        self.chi.reserve(n);
    }

    /// Store a node that is not stored yet.
    pub fn insert(&mut self, key: u64, phi: f64, chi: PhaseId) {
        self.index.insert(key, self.keys.len() as u32);
        self.keys.push(key);
        self.phi.push(phi);
        self.chi.push(chi);
    }
}
