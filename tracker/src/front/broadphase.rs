//! Broad phase: an incremental uniform hash grid of triangle bounding boxes (static boxes, or
//! swept boxes of moving triangles), the "simple regular grid" of paper 000 §8. Each triangle
//! is listed in every cell its box overlaps; queries return exactly the triangles whose stored
//! box overlaps the query box (closed boxes, exact comparisons), sorted, so results never
//! depend on hashing or insertion order.
//!
//! Never missing an overlap rests on monotonicity: `x ↦ floor(x / cell)` is monotone in
//! floating point, so two overlapping boxes have overlapping cell ranges.

use glam::DVec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Integer cell coordinates.
type Cell = [i32; 3];

/// Hash grid of triangle boxes keyed by triangle id.
#[derive(Clone, Debug)]
pub struct TriangleGrid {
    inv_cell: f64,
    cells: HashMap<Cell, Vec<u32>, BuildHasherDefault<CellHasher>>,
    /// Stored box of each inserted triangle (`None`: absent), indexed by triangle id.
    boxes: Vec<Option<(DVec3, DVec3)>>,
    len: usize,
}

/// Most cells one box may be listed in; larger boxes make queries fall back to a scan.
const MAX_CELLS_PER_QUERY: i64 = 4096;

impl TriangleGrid {
    /// An empty grid with cubic cells of side `cell_size` (about the typical box size is best).
    /// Non-positive or non-finite sizes are replaced by 1.
    pub fn new(cell_size: f64) -> Self {
        let cell = if cell_size.is_finite() && cell_size > 0.0 {
            cell_size
        } else {
            1.0
        };
        TriangleGrid {
            inv_cell: 1.0 / cell,
            cells: HashMap::default(),
            boxes: Vec::new(),
            len: 0,
        }
    }

    /// Number of triangles stored.
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` when no triangle is stored.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The stored box of `triangle`, if present.
    pub fn get(&self, triangle: u32) -> Option<(DVec3, DVec3)> {
        self.boxes.get(triangle as usize).copied().flatten()
    }

    /// Stores `triangle` with box `[lo, hi]`, replacing its previous box if any.
    pub fn insert(&mut self, triangle: u32, lo: DVec3, hi: DVec3) {
        self.remove(triangle);
        let i = triangle as usize;
        if self.boxes.len() <= i {
            self.boxes.resize(i + 1, None);
        }
        self.boxes[i] = Some((lo, hi));
        self.len += 1;
        let (a, b) = (self.cell(lo), self.cell(hi));
        if cell_count(a, b) > MAX_CELLS_PER_QUERY {
            // Oversized box: kept in one overflow cell list that every query scans.
            self.cells.entry(OVERFLOW).or_default().push(triangle);
            return;
        }
        for_cells(a, b, |c| self.cells.entry(c).or_default().push(triangle));
    }

    /// Removes `triangle` (no effect if absent).
    pub fn remove(&mut self, triangle: u32) {
        let Some((lo, hi)) = self.get(triangle) else {
            return;
        };
        self.boxes[triangle as usize] = None;
        self.len -= 1;
        let (a, b) = (self.cell(lo), self.cell(hi));
        let drop_from = |c: Cell, cells: &mut HashMap<_, Vec<u32>, _>| {
            if let Some(list) = cells.get_mut(&c) {
                if let Some(k) = list.iter().position(|&t| t == triangle) {
                    list.swap_remove(k);
                }
                if list.is_empty() {
                    cells.remove(&c);
                }
            }
        };
        if cell_count(a, b) > MAX_CELLS_PER_QUERY {
            drop_from(OVERFLOW, &mut self.cells);
            return;
        }
        for_cells(a, b, |c| drop_from(c, &mut self.cells));
    }

    /// Writes into `out` (cleared first) the triangles whose stored box overlaps the closed box
    /// `[lo, hi]`, sorted and deduplicated.
    pub fn query(&self, lo: DVec3, hi: DVec3, out: &mut Vec<u32>) {
        out.clear();
        let (a, b) = (self.cell(lo), self.cell(hi));
        let overlaps = |t: u32| {
            self.get(t)
                .is_some_and(|(l, h)| l.cmple(hi).all() && lo.cmple(h).all())
        };
        if cell_count(a, b) > (self.cells.len() as i64).min(MAX_CELLS_PER_QUERY) {
            out.extend((0..self.boxes.len() as u32).filter(|&t| overlaps(t)));
            return;
        }
        for_cells(a, b, |c| {
            if let Some(list) = self.cells.get(&c) {
                out.extend(list.iter().copied().filter(|&t| overlaps(t)));
            }
        });
        if let Some(list) = self.cells.get(&OVERFLOW) {
            out.extend(list.iter().copied().filter(|&t| overlaps(t)));
        }
        out.sort_unstable();
        out.dedup();
    }

    fn cell(&self, p: DVec3) -> Cell {
        // `as` saturates (and maps NaN to 0); the range is kept clear of `OVERFLOW`.
        let c = |x: f64| ((x * self.inv_cell).floor() as i32).clamp(-(1 << 30), 1 << 30);
        [c(p.x), c(p.y), c(p.z)]
    }
}

/// The cell key holding oversized boxes; outside the range [`TriangleGrid::cell`] produces.
const OVERFLOW: Cell = [i32::MIN; 3];

fn cell_count(a: Cell, b: Cell) -> i64 {
    (0..3)
        .map(|k| (b[k] as i64 - a[k] as i64 + 1).max(0))
        .product()
}

fn for_cells(a: Cell, b: Cell, mut f: impl FnMut(Cell)) {
    for z in a[2]..=b[2] {
        for y in a[1]..=b[1] {
            for x in a[0]..=b[0] {
                f([x, y, z]);
            }
        }
    }
}

/// FxHash-style multiplicative hasher for cell keys: fast, and deterministic across runs
/// (results never depend on it anyway, see the module doc).
#[derive(Default, Clone, Copy)]
pub struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_i32(&mut self, i: i32) {
        self.write_u64(i as u32 as u64);
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// A broad phase built once from a fixed set of boxes (the swept boxes of one motion): the
/// `(cell, triangle)` incidences sorted in parallel, each cell's run found through a hash map. Faster to build
/// than [`TriangleGrid`] for whole-mesh passes and answers queries the same way (exact box
/// overlap, sorted output).
#[derive(Clone, Debug)]
pub struct StaticGrid {
    inv_cell: f64,
    /// `(packed cell, triangle)`, sorted.
    entries: Vec<(u64, u32)>,
    /// Start and end in `entries` of each occupied cell's run.
    runs: HashMap<u64, (u32, u32), BuildHasherDefault<CellHasher>>,
    /// Triangles whose boxes span too many cells, scanned by every query.
    oversized: Vec<u32>,
    boxes: Vec<(DVec3, DVec3)>,
}

/// Cell coordinates are clamped to `±CELL_RANGE` for packing; clamping is monotone, so the
/// overlap argument of the module doc still holds (far boxes only share more cells).
const CELL_RANGE: i64 = (1 << 20) - 1;

impl StaticGrid {
    /// Grid over `boxes` (box `i` belongs to triangle `i`) with cubic cells of side
    /// `cell_size` (non-positive or non-finite: 1).
    pub fn build(boxes: Vec<(DVec3, DVec3)>, cell_size: f64) -> Self {
        let cell = if cell_size.is_finite() && cell_size > 0.0 {
            cell_size
        } else {
            1.0
        };
        let inv_cell = 1.0 / cell;
        let range = |b: &(DVec3, DVec3)| (packed_cell(b.0, inv_cell), packed_cell(b.1, inv_cell));
        let oversized: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&t| {
                let (a, b) = range(&boxes[t as usize]);
                cell_count_packed(a, b) > MAX_CELLS_PER_QUERY
            })
            .collect();
        let mut entries: Vec<(u64, u32)> = boxes
            .par_iter()
            .enumerate()
            .flat_map_iter(|(t, b)| {
                let (a, c) = range(b);
                let n = cell_count_packed(a, c);
                let mut keys = Vec::with_capacity(if n > MAX_CELLS_PER_QUERY {
                    0
                } else {
                    n as usize
                });
                if n <= MAX_CELLS_PER_QUERY {
                    for_packed_cells(a, c, |k| keys.push((k, t as u32)));
                }
                keys.into_iter()
            })
            .collect();
        entries.par_sort_unstable();
        let mut runs: HashMap<u64, (u32, u32), BuildHasherDefault<CellHasher>> = HashMap::default();
        let mut start = 0;
        for i in 1..=entries.len() {
            if i == entries.len() || entries[i].0 != entries[start].0 {
                runs.insert(entries[start].0, (start as u32, i as u32));
                start = i;
            }
        }
        StaticGrid {
            inv_cell,
            entries,
            runs,
            oversized,
            boxes,
        }
    }

    /// The stored boxes, indexed by triangle.
    pub fn boxes(&self) -> &[(DVec3, DVec3)] {
        &self.boxes
    }

    /// Writes into `out` (cleared first) the triangles whose box overlaps the closed box
    /// `[lo, hi]`, sorted and deduplicated.
    pub fn query(&self, lo: DVec3, hi: DVec3, out: &mut Vec<u32>) {
        out.clear();
        let overlaps = |t: u32| {
            let (l, h) = self.boxes[t as usize];
            l.cmple(hi).all() && lo.cmple(h).all()
        };
        let (a, b) = (
            packed_cell(lo, self.inv_cell),
            packed_cell(hi, self.inv_cell),
        );
        if cell_count_packed(a, b) > MAX_CELLS_PER_QUERY {
            out.extend((0..self.boxes.len() as u32).filter(|&t| overlaps(t)));
            return;
        }
        for_packed_cells(a, b, |k| {
            if let Some(&(start, end)) = self.runs.get(&k) {
                out.extend(
                    self.entries[start as usize..end as usize]
                        .iter()
                        .map(|e| e.1)
                        .filter(|&t| overlaps(t)),
                );
            }
        });
        out.extend(self.oversized.iter().copied().filter(|&t| overlaps(t)));
        out.sort_unstable();
        out.dedup();
    }
}

/// Cell of `p`, each coordinate clamped to `±CELL_RANGE` and offset to be non-negative.
fn packed_cell(p: DVec3, inv_cell: f64) -> [i64; 3] {
    let c = |x: f64| ((x * inv_cell).floor() as i64).clamp(-CELL_RANGE, CELL_RANGE) + CELL_RANGE;
    [c(p.x), c(p.y), c(p.z)]
}

fn cell_count_packed(a: [i64; 3], b: [i64; 3]) -> i64 {
    (0..3).map(|k| (b[k] - a[k] + 1).max(0)).product()
}

fn for_packed_cells(a: [i64; 3], b: [i64; 3], mut f: impl FnMut(u64)) {
    for z in a[2]..=b[2] {
        for y in a[1]..=b[1] {
            for x in a[0]..=b[0] {
                f(((z as u64) << 42) | ((y as u64) << 21) | x as u64);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::front::predicates::tests::Rng;

    #[test]
    fn query_matches_brute_force_through_inserts_and_removals() {
        let mut rng = Rng(3);
        let mut grid = TriangleGrid::new(0.1);
        let mut boxes: Vec<Option<(DVec3, DVec3)>> = vec![None; 300];
        for step in 0..2000 {
            let t = (rng.next_u64() % 300) as u32;
            if step % 3 == 0 {
                grid.remove(t);
                boxes[t as usize] = None;
            } else {
                let c = rng.v();
                // Mostly small boxes, some spanning many cells, a few oversized.
                let size = match step % 50 {
                    0 => 50.0,
                    1..=5 => 0.5,
                    _ => 0.05,
                };
                let h = (rng.v().abs() * size).max(DVec3::ZERO);
                grid.insert(t, c - h, c + h);
                boxes[t as usize] = Some((c - h, c + h));
            }
            let (qc, qh) = (rng.v(), rng.v().abs() * 0.2);
            let mut out = Vec::new();
            grid.query(qc - qh, qc + qh, &mut out);
            let expected: Vec<u32> = (0..300u32)
                .filter(|&i| {
                    boxes[i as usize]
                        .is_some_and(|(l, h)| l.cmple(qc + qh).all() && (qc - qh).cmple(h).all())
                })
                .collect();
            assert_eq!(out, expected);
            assert_eq!(grid.len(), boxes.iter().flatten().count());
        }
    }

    #[test]
    fn static_grid_matches_brute_force() {
        let mut rng = Rng(12);
        let boxes: Vec<(DVec3, DVec3)> = (0..500)
            .map(|i| {
                let c = rng.v();
                let size = if i % 97 == 0 { 40.0 } else { 0.08 };
                let h = rng.v().abs() * size;
                (c - h, c + h)
            })
            .collect();
        let grid = StaticGrid::build(boxes.clone(), 0.1);
        let mut out = Vec::new();
        for _ in 0..500 {
            let (qc, qh) = (rng.v(), rng.v().abs() * 0.3);
            grid.query(qc - qh, qc + qh, &mut out);
            let expected: Vec<u32> = (0..500u32)
                .filter(|&i| {
                    let (l, h) = boxes[i as usize];
                    l.cmple(qc + qh).all() && (qc - qh).cmple(h).all()
                })
                .collect();
            assert_eq!(out, expected);
        }
    }

    #[test]
    fn touching_boxes_are_found_across_cell_boundaries() {
        let mut grid = TriangleGrid::new(0.5);
        // Box ending exactly on a cell boundary, query box starting exactly there.
        grid.insert(7, DVec3::splat(0.0), DVec3::splat(0.5));
        let mut out = Vec::new();
        grid.query(DVec3::splat(0.5), DVec3::splat(0.9), &mut out);
        assert_eq!(out, vec![7]);
        grid.query(DVec3::splat(0.5f64.next_up()), DVec3::splat(0.9), &mut out);
        assert!(out.is_empty());
        let fixed = StaticGrid::build(vec![(DVec3::splat(0.0), DVec3::splat(0.5))], 0.5);
        fixed.query(DVec3::splat(0.5), DVec3::splat(0.9), &mut out);
        assert_eq!(out, vec![0]);
    }
}
