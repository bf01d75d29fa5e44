//! A Voronoi foam: random seeds in a box, each owning the points nearer to it than to any other
//! seed (paper 000 §8.4, Fig. 24: mean-curvature flow of a foam of 2000 regions in a cube).
//! Cell `k` is phase `k`. A bucket grid keeps each query near O(1) for thousands of seeds.

use glam::{DVec3, IVec3};
use polyphase_grid::PhaseId;

/// Seeds in a box with a bucket grid over them.
#[derive(Clone, Debug, PartialEq)]
pub struct Voronoi {
    seeds: Vec<DVec3>,
    lo: DVec3,
    hi: DVec3,
    /// Bucket edge length.
    size: f64,
    dims: IVec3,
    /// Seed indices per bucket (x fastest), each list ascending.
    buckets: Vec<Vec<u32>>,
}

impl Voronoi {
    /// `n` seeds placed uniformly in `[lo, hi]` by a generator started from `seed`.
    pub fn random(n: usize, seed: u64, lo: DVec3, hi: DVec3) -> Voronoi {
        let mut rng = SplitMix64(seed);
        let seeds = (0..n)
            .map(|_| {
                let u = DVec3::new(rng.unit(), rng.unit(), rng.unit());
                lo + u * (hi - lo)
            })
            .collect();
        Voronoi::new(seeds, lo, hi)
    }

    /// The foam of `seeds` (at least one) inside `[lo, hi]`.
    pub fn new(seeds: Vec<DVec3>, lo: DVec3, hi: DVec3) -> Voronoi {
        let extent = hi - lo;
        // About one seed per bucket.
        let size = (extent.x * extent.y * extent.z / seeds.len().max(1) as f64).cbrt();
        let dims = (extent / size).ceil().as_ivec3().max(IVec3::ONE);
        let mut buckets = vec![Vec::new(); (dims.x * dims.y * dims.z) as usize];
        let mut grid = Voronoi {
            seeds,
            lo,
            hi,
            size,
            dims,
            buckets: Vec::new(),
        };
        for (i, &s) in grid.seeds.iter().enumerate() {
            buckets[grid.index(grid.bucket(s))].push(i as u32);
        }
        grid.buckets = buckets;
        grid
    }

    /// The seeds, cell `k` around seed `k`.
    pub fn seeds(&self) -> &[DVec3] {
        &self.seeds
    }

    fn bucket(&self, x: DVec3) -> IVec3 {
        ((x - self.lo) / self.size)
            .floor()
            .as_ivec3()
            .clamp(IVec3::ZERO, self.dims - 1)
    }

    fn index(&self, b: IVec3) -> usize {
        (b.x + self.dims.x * (b.y + self.dims.y * b.z)) as usize
    }

    /// Calls `visit` with every seed index in buckets that may hold a point within `radius(…)`
    /// of `x`, ring by ring outwards; `radius` is asked again after each ring (it may shrink).
    fn visit_near(&self, x: DVec3, mut radius: impl FnMut() -> f64, mut visit: impl FnMut(u32)) {
        let home = self.bucket(x);
        // A point outside the box is clamped into its nearest bucket, which it is this far from.
        let outside = ((self.lo - x).max(DVec3::ZERO) + (x - self.hi).max(DVec3::ZERO)).length();
        let rings = self.dims.max_element();
        for r in 0..=rings {
            // A bucket in ring r is at least (r − 1) bucket lengths from a point of the home
            // bucket.
            if r >= 2 && (r - 1) as f64 * self.size - outside > radius() {
                return;
            }
            for dz in -r..=r {
                for dy in -r..=r {
                    // Inside the shell only the two x ends belong to ring r.
                    let step = if dz.abs() == r || dy.abs() == r {
                        1
                    } else {
                        (2 * r).max(1)
                    };
                    for dx in (-r..=r).step_by(step as usize) {
                        let b = home + IVec3::new(dx, dy, dz);
                        if b.cmplt(IVec3::ZERO).any() || b.cmpge(self.dims).any() {
                            continue;
                        }
                        for &i in &self.buckets[self.index(b)] {
                            visit(i);
                        }
                    }
                }
            }
        }
    }

    /// The cell holding `x`: its nearest seed (the lower index on a tie).
    pub fn cell(&self, x: DVec3) -> usize {
        let mut best = (f64::INFINITY, usize::MAX);
        let found = std::cell::Cell::new(f64::INFINITY);
        self.visit_near(
            x,
            || found.get(),
            |i| {
                let d = (x - self.seeds[i as usize]).length_squared();
                if (d, i as usize) < best {
                    best = (d, i as usize);
                    found.set(d.sqrt());
                }
            },
        );
        best.1
    }

    /// The cell holding `x`, the distance to its boundary within the domain (the nearest
    /// bisector plane: exact for a convex cell) and that plane's unit normal, pointing out of
    /// the cell; `None` for the normal with a single seed.
    pub fn boundary(&self, x: DVec3) -> (usize, f64, Option<DVec3>) {
        let i = self.cell(x);
        let si = self.seeds[i];
        let b = (x - si).length();
        let best = std::cell::Cell::new((f64::INFINITY, None));
        // A seed at distance a has its bisector at least (a − b)/2 from x (triangle
        // inequality), so seeds beyond b + 2·best cannot bring a nearer plane.
        self.visit_near(
            x,
            || b + 2.0 * best.get().0,
            |j| {
                let sj = self.seeds[j as usize];
                let gap = sj - si;
                let len = gap.length();
                if j as usize == i || len == 0.0 {
                    return;
                }
                let d = ((x - sj).length_squared() - (x - si).length_squared()) / (2.0 * len);
                if d < best.get().0 {
                    best.set((d, Some(gap / len)));
                }
            },
        );
        let (d, n) = best.get();
        (i, d.max(0.0), n)
    }

    /// The exact volume of every cell within the box: each cell is the box clipped by the
    /// bisector planes of the seeds near enough to cut it (a convex polytope), summed as
    /// pyramids from its seed over its faces.
    pub fn cell_volumes(&self) -> Vec<f64> {
        (0..self.seeds.len()).map(|i| self.cell_volume(i)).collect()
    }

    fn cell_volume(&self, i: usize) -> f64 {
        let si = self.seeds[i];
        let (lo, hi) = (self.lo, self.hi);
        let corner = |x: bool, y: bool, z: bool| {
            DVec3::new(
                if x { hi.x } else { lo.x },
                if y { hi.y } else { lo.y },
                if z { hi.z } else { lo.z },
            )
        };
        let mut faces: Vec<Face> = (0..3)
            .flat_map(|a| [false, true].map(|up| (a, up)))
            .map(|(a, up)| {
                // The face's four corners in cyclic order: the other two axes walk the square.
                let (b, c) = ((a + 1) % 3, (a + 2) % 3);
                let points = [(false, false), (true, false), (true, true), (false, true)]
                    .map(|(u, v)| {
                        let mut f = [false; 3];
                        f[a] = up;
                        f[b] = u;
                        f[c] = v;
                        corner(f[0], f[1], f[2])
                    })
                    .to_vec();
                let mut normal = DVec3::ZERO;
                normal[a] = if up { 1.0 } else { -1.0 };
                Face { normal, points }
            })
            .collect();
        let mut order: Vec<usize> = (0..self.seeds.len()).filter(|&j| j != i).collect();
        order.sort_by(|&a, &b| {
            let da = (self.seeds[a] - si).length_squared();
            let db = (self.seeds[b] - si).length_squared();
            da.total_cmp(&db).then(a.cmp(&b))
        });
        for j in order {
            let gap = self.seeds[j] - si;
            let reach = faces
                .iter()
                .flat_map(|f| &f.points)
                .map(|p| (*p - si).length())
                .fold(0.0, f64::max);
            // The bisector lies |gap|/2 from the seed: it cannot cut a cell within that reach,
            // nor can any farther seed's.
            if 0.5 * gap.length() >= reach {
                break;
            }
            let n = gap.normalize();
            let c = n.dot(si + 0.5 * gap);
            faces = clip(&faces, n, c);
        }
        faces
            .iter()
            .map(|f| f.area() * f.normal.dot(f.points[0] - si) / 3.0)
            .sum()
    }

    /// (φ, χ) as the contouring tracker samples them: the distance to the cell's boundary
    /// and the cell's phase.
    pub fn sample(&self, x: DVec3) -> (f64, PhaseId) {
        let (i, d, _) = self.boundary(x);
        (d, i as PhaseId)
    }
}

/// A planar convex face of a cell: its outward unit normal and its corners in cyclic order.
struct Face {
    normal: DVec3,
    points: Vec<DVec3>,
}

impl Face {
    fn area(&self) -> f64 {
        let p = &self.points;
        if p.len() < 3 {
            return 0.0;
        }
        let twice: DVec3 = (1..p.len() - 1)
            .map(|k| (p[k] - p[0]).cross(p[k + 1] - p[0]))
            .sum();
        0.5 * twice.length()
    }
}

/// The convex polytope `faces` cut to its part with `n·x ≤ c`: each face clipped
/// (Sutherland–Hodgman), and the cut closed by a new face of the crossing points.
fn clip(faces: &[Face], n: DVec3, c: f64) -> Vec<Face> {
    let mut out = Vec::with_capacity(faces.len() + 1);
    let mut cut: Vec<DVec3> = Vec::new();
    for f in faces {
        let mut points = Vec::with_capacity(f.points.len() + 1);
        for k in 0..f.points.len() {
            let (a, b) = (f.points[k], f.points[(k + 1) % f.points.len()]);
            let (da, db) = (n.dot(a) - c, n.dot(b) - c);
            if da <= 0.0 {
                points.push(a);
            }
            if (da <= 0.0) != (db <= 0.0) {
                let x = a + (b - a) * (da / (da - db));
                points.push(x);
                cut.push(x);
            }
        }
        if points.len() >= 3 {
            out.push(Face {
                normal: f.normal,
                points,
            });
        }
    }
    if cut.len() >= 3 {
        // Order the crossing points by angle around their centre in the cutting plane.
        let centre = cut.iter().sum::<DVec3>() / cut.len() as f64;
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let angle = |p: &DVec3| (*p - centre).dot(v).atan2((*p - centre).dot(u));
        cut.sort_by(|a, b| angle(a).total_cmp(&angle(b)));
        out.push(Face {
            normal: n,
            points: cut,
        });
    }
    out
}

/// SplitMix64 (Steele, Lea & Flood 2014): a small generator whose stream depends only on the
/// seed, so a foam is the same on every machine.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) from the top 53 bits.
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The brute-force answer: the nearest seed and the nearest bisector plane over all seeds.
    fn brute(v: &Voronoi, x: DVec3) -> (usize, f64) {
        let s = v.seeds();
        let i = (0..s.len())
            .min_by(|&a, &b| {
                ((x - s[a]).length_squared(), a)
                    .partial_cmp(&((x - s[b]).length_squared(), b))
                    .unwrap()
            })
            .unwrap();
        let d = (0..s.len())
            .filter(|&j| j != i)
            .map(|j| {
                ((x - s[j]).length_squared() - (x - s[i]).length_squared())
                    / (2.0 * (s[j] - s[i]).length())
            })
            .fold(f64::INFINITY, f64::min);
        (i, d)
    }

    #[test]
    fn buckets_give_the_brute_force_cell_and_distance() {
        let v = Voronoi::random(300, 7, DVec3::ZERO, DVec3::new(1.0, 0.5, 0.8));
        let mut rng = SplitMix64(99);
        for _ in 0..2000 {
            let x = DVec3::new(rng.unit(), 0.5 * rng.unit(), 0.8 * rng.unit());
            let (i, d, _) = v.boundary(x);
            let (bi, bd) = brute(&v, x);
            assert_eq!(i, bi, "at {x}");
            // The same formula over the same seeds: equal up to the order of the minimum.
            assert!((d - bd).abs() <= 1e-12, "at {x}: {d} against {bd}");
        }
    }

    #[test]
    fn the_distance_is_to_the_bisector_of_two_seeds() {
        let v = Voronoi::new(
            vec![DVec3::new(0.25, 0.5, 0.5), DVec3::new(0.75, 0.5, 0.5)],
            DVec3::ZERO,
            DVec3::ONE,
        );
        let (i, d, n) = v.boundary(DVec3::new(0.4, 0.9, 0.1));
        assert_eq!(i, 0);
        assert!((d - 0.1).abs() < 1e-15);
        assert_eq!(n, Some(DVec3::X));
        assert_eq!(v.cell(DVec3::new(0.6, 0.1, 0.9)), 1);
    }

    #[test]
    fn cell_volumes_fill_the_box_and_halve_it_for_two_seeds() {
        let two = Voronoi::new(
            vec![DVec3::new(0.3, 0.5, 0.5), DVec3::new(0.5, 0.5, 0.5)],
            DVec3::ZERO,
            DVec3::new(1.0, 2.0, 1.0),
        );
        // The bisector x = 0.4 splits the 1 × 2 × 1 box into 0.8 and 1.2.
        let v = two.cell_volumes();
        assert!(
            (v[0] - 0.8).abs() < 1e-14 && (v[1] - 1.2).abs() < 1e-14,
            "{v:?}"
        );
        let foam = Voronoi::random(200, 5, DVec3::ZERO, DVec3::new(1.0, 0.7, 0.9));
        let v = foam.cell_volumes();
        // The cells tile the box: their sum is its volume up to rounding.
        assert!((v.iter().sum::<f64>() - 0.63).abs() < 1e-12);
        assert!(v.iter().all(|&x| x > 0.0));
        // Against the fraction of 20 000 random points each cell holds: the binomial standard
        // error of the largest cell (about 1.5 % of the box) is 9e-4 of the box; 5σ.
        let mut rng = SplitMix64(11);
        let mut count = vec![0usize; v.len()];
        let n = 20_000;
        for _ in 0..n {
            let x = DVec3::new(rng.unit(), 0.7 * rng.unit(), 0.9 * rng.unit());
            count[foam.cell(x)] += 1;
        }
        for (k, &c) in count.iter().enumerate() {
            let sampled = c as f64 / n as f64 * 0.63;
            assert!((sampled - v[k]).abs() < 5.0 * 9e-4 * 0.63, "cell {k}");
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_foam() {
        let a = Voronoi::random(50, 3, DVec3::ZERO, DVec3::ONE);
        let b = Voronoi::random(50, 3, DVec3::ZERO, DVec3::ONE);
        let c = Voronoi::random(50, 4, DVec3::ZERO, DVec3::ONE);
        assert_eq!(a.seeds(), b.seeds());
        assert_ne!(a.seeds(), c.seeds());
        assert!(a
            .seeds()
            .iter()
            .all(|s| s.cmpge(DVec3::ZERO).all() && s.cmplt(DVec3::ONE).all()));
    }
}
