//! Redistancing the MD tree after contouring (paper 004 §6.4): exact distances to the new
//! mesh at the corners of the interface cells, then first-order fast marching (Sethian 1996,
//! the paper's [39]) outward over the finest level; χ is left unchanged.
//!
//! Band: the march covers every node of the finest level, i.e. the corners of all unit
//! leaves. By the split rule (φ(centre) < 3·h_c at h_c = 2h) this contains every node closer
//! than 6h − √3·h ≈ 4.3h to the interface, typically ≈ 6h. Nodes of coarser leaves keep the
//! value sampled while building (exact, or a lower bound of the distance, per the
//! [`crate::PhaseSampler`] contract): they are ≥ 4.3h away, where the solver only needs the
//! phase and a rough distance.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::DVec3;
use rayon::prelude::*;

use crate::contour::tree::{Cell, MdTree, LEAF};

const NONE: u32 = u32::MAX;

impl MdTree {
    /// §6.4: exact distances (given function = distance to the NEW mesh) at the nodes of
    /// interface cells, fast marching outward over the finest level (see the module doc for
    /// the band); χ unchanged.
    pub fn redistance(&mut self, exact_distance: &(dyn Fn(DVec3) -> f64 + Sync)) {
        self.dist = self.redistanced(exact_distance);
    }

    /// The node distances [`MdTree::redistance`] would leave, without changing the tree: a
    /// tracker keeps them beside it and computes them only when φ is read.
    pub fn redistanced(&self, exact_distance: &(dyn Fn(DVec3) -> f64 + Sync)) -> Vec<f64> {
        let lat = self.lattice;
        let unit = |c: &&Cell| c.child == LEAF && c.size == 1;
        // Finest-level nodes, numbered in node-store (insertion, so deterministic) order.
        let mut local = vec![NONE; self.nodes.len()];
        for c in self.cells.iter().filter(unit) {
            for &s in &c.slots {
                local[s as usize] = 0;
            }
        }
        let mut slots = Vec::new();
        for (s, l) in local.iter_mut().enumerate() {
            if *l != NONE {
                *l = slots.len() as u32;
                slots.push(s);
            }
        }
        // Lattice neighbours (−x, +x, −y, +y, −z, +z) along the edges of unit leaves.
        let mut nbr = vec![[NONE; 6]; slots.len()];
        for c in self.cells.iter().filter(unit) {
            for (k, &s) in c.slots.iter().enumerate() {
                for axis in 0..3 {
                    if k & (1 << axis) == 0 {
                        let (a, b) = (local[s as usize], local[c.slots[k | (1 << axis)] as usize]);
                        nbr[a as usize][2 * axis + 1] = b;
                        nbr[b as usize][2 * axis] = a;
                    }
                }
            }
        }
        let mut seeds: Vec<u32> = self
            .interface
            .iter()
            .flat_map(|&c| self.cells[c as usize].slots.map(|s| local[s as usize]))
            .collect();
        seeds.sort_unstable();
        seeds.dedup();
        let keys = &self.nodes.keys;
        let exact: Vec<f64> = seeds
            .par_iter()
            .map(|&i| exact_distance(lat.pos(keys[slots[i as usize]])).max(0.0))
            .collect();

        let mut value = vec![f64::INFINITY; slots.len()];
        let mut fixed = vec![false; slots.len()];
        let mut done = vec![false; slots.len()];
        // Keys: non-negative f64 order like their bit patterns; ties break on the node index.
        let mut heap = BinaryHeap::new();
        for (&i, &d) in seeds.iter().zip(&exact) {
            value[i as usize] = d;
            fixed[i as usize] = true;
            heap.push(Reverse((d.to_bits(), i)));
        }
        let h = lat.h;
        while let Some(Reverse((bits, i))) = heap.pop() {
            let i = i as usize;
            if done[i] || bits != value[i].to_bits() {
                continue;
            }
            done[i] = true;
            for &j in &nbr[i] {
                let j = j as usize;
                if j == NONE as usize || done[j] || fixed[j] {
                    continue;
                }
                let mut a = [f64::INFINITY; 3];
                for (d, &k) in nbr[j].iter().enumerate() {
                    if k != NONE && done[k as usize] {
                        a[d / 2] = a[d / 2].min(value[k as usize]);
                    }
                }
                let u = eikonal(a, h);
                if u < value[j] {
                    value[j] = u;
                    heap.push(Reverse((u.to_bits(), j as u32)));
                }
            }
        }
        let mut dist = self.dist.clone();
        for (&s, &v) in slots.iter().zip(&value) {
            if v.is_finite() {
                dist[s] = v;
            }
        }
        dist
    }
}

/// First-order upwind solution u of Σ_axes max(u − a_axis, 0)² = h² (unit speed).
fn eikonal(mut a: [f64; 3], h: f64) -> f64 {
    a.sort_by(f64::total_cmp);
    let mut u = a[0] + h;
    if u > a[1] {
        let d = a[0] - a[1];
        u = 0.5 * (a[0] + a[1] + (2.0 * h * h - d * d).max(0.0).sqrt());
        if u > a[2] {
            let s = a[0] + a[1] + a[2];
            let q = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
            u = (s + (s * s - 3.0 * (q - h * h)).max(0.0).sqrt()) / 3.0;
        }
    }
    u
}
