//! Collision response (paper 000 §4.2): turns proposed end positions into an
//! intersection-free linear motion, following the cloth scheme of Bridson et al. 2002 with the
//! impact-zone fallback of Harmon et al. 2008.
//!
//! 1. Proximity repulsion: pairs closer than the thickness `h` at the start may approach only
//!    down to `h / 2` (no approach at all if already closer), by inelastic impulses.
//! 2. CCD impulses: for every contact [`super::collision::detect`] finds, an inelastic impulse along the contact
//!    normal (triangle normal, or the edges' cross product, at the contact time) makes the end
//!    separation along it at least half the start separation (capped at `h / 2`); repeated.
//! 3. Impact zones: the vertices of remaining contacts are merged (union–find) into zones
//!    that move as rigid translations by their mean proposed displacement (linear momentum is
//!    kept). With linear trajectories a pure translation keeps every pair inside a zone at a
//!    constant offset, so zones can only collide with each other, and merging repeats until
//!    CCD finds nothing. Rotations are dropped: linearly interpolated rotations are not
//!    rigid and could collide inside a zone.
//!
//! All vertices weigh the same, except that coordinates pinned by a domain wall
//! ([`resolve_pinned`]) take no share of an impulse (infinite mass along that axis). Impulses are applied one contact at a time in the
//! deterministic order of [`super::collision::detect`], so results do not depend on the thread count.

pub mod proximity;

use super::ccd::{self, Hit};
use super::collision::{is_removed, Contact, Detector};
use glam::DVec3;
use proximity::{point_triangle_closest, proximity_pairs, segment_segment_closest};

/// Parameters of [`resolve`].
#[derive(Clone, Debug, PartialEq)]
pub struct CollisionParams {
    /// Proximity thickness `h` in mesh units (default `1e-5`, small against the edge lengths of
    /// unit-cube scenes): pairs closer than `h` at the start may not approach below `h / 2`.
    pub thickness: f64,
    /// Sweeps of CCD impulses before falling back to impact zones (default 8).
    pub impulse_iterations: usize,
    /// Impact-zone merge rounds before giving up (default 64).
    pub zone_iterations: usize,
    /// Whether an impact zone holding a pinned coordinate moves without that coordinate
    /// (sliding along the wall) instead of failing the motion (default false). Failing halves
    /// the step, and in a fluid's velocity the halved steps mostly resolve by impulses: with
    /// zones sliding instead, the front `dambreak_column` at 64 cells gained 0.87 % of its water
    /// by frame 15 (zones move with their members' mean). Mesh-driven flows slide: a foam's
    /// films all end on walls, and there the halving failed to its deepest level and dropped
    /// the motion, at 2.7 of the 256-region foam's 5.3 s per substep (one thread).
    pub pinned_zones_slide: bool,
}

impl Default for CollisionParams {
    fn default() -> Self {
        CollisionParams {
            thickness: 1e-5,
            impulse_iterations: 8,
            zone_iterations: 64,
            pinned_zones_slide: false,
        }
    }
}

/// What [`resolve`] did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ResolveStats {
    /// Proximity pairs found at the start.
    pub proximity_pairs: usize,
    /// Contact detections run (impulse sweeps plus zone rounds, the final clean one included).
    pub iterations: usize,
    /// Contacts handled by impulses or zones, summed over iterations.
    pub contacts: usize,
    /// Impact zones (of two or more vertices) in the final motion.
    pub impact_zones: usize,
}

/// Why [`resolve`] failed; the caller should cut the step.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("collision resolution failed: {cause}")]
pub struct Unresolved {
    pub cause: UnresolvedCause,
}

/// The cause inside [`Unresolved`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum UnresolvedCause {
    #[error("x0 has {x0} vertices but x1 has {x1}")]
    LengthMismatch { x0: usize, x1: usize },
    #[error("triangle {triangle} refers to a vertex out of range")]
    BadTriangle { triangle: usize },
    #[error("non-finite position at vertex {vertex}")]
    NonFinite { vertex: usize },
    #[error("{contacts} contacts remain after {rounds} impact-zone rounds")]
    ContactsRemain { contacts: usize, rounds: usize },
    #[error("an impact zone moved pinned vertex {vertex}")]
    PinnedMoved { vertex: usize },
}

/// Changes the proposed end positions `x1` so that the linear motion from `x0` (which must be
/// free of contacts) has no contact (module doc). Removed triangle slots
/// ([`super::collision::is_removed`]) are ignored. On error `x1` holds the last attempt.
pub fn resolve(
    triangles: &[[u32; 3]],
    x0: &[DVec3],
    x1: &mut [DVec3],
    params: &CollisionParams,
) -> Result<ResolveStats, Unresolved> {
    resolve_pinned(triangles, x0, x1, &[], params)
}

/// [`resolve`] where `pinned[v][k]` holds coordinate `k` of vertex `v` where `x1` has it
/// (a vertex sliding on a wall keeps its wall coordinate): impulses move only free
/// coordinates. Impact zones still translate their pinned members whole, so a result that
/// moved a pinned coordinate is an error and the caller cuts the step. An empty `pinned`
/// pins nothing.
pub fn resolve_pinned(
    triangles: &[[u32; 3]],
    x0: &[DVec3],
    x1: &mut [DVec3],
    pinned: &[[bool; 3]],
    params: &CollisionParams,
) -> Result<ResolveStats, Unresolved> {
    let proposed = x1[..pinned.len().min(x1.len())].to_vec();
    let stats = resolve_with(triangles, x0, x1, Pins(pinned), params)?;
    if let Some(vertex) =
        (0..proposed.len()).find(|&v| (0..3).any(|k| pinned[v][k] && x1[v][k] != proposed[v][k]))
    {
        return Err(Unresolved {
            cause: UnresolvedCause::PinnedMoved { vertex },
        });
    }
    Ok(stats)
}

/// Which coordinates impulses may move.
#[derive(Clone, Copy)]
struct Pins<'a>(&'a [[bool; 3]]);

impl Pins<'_> {
    /// 1 for each free coordinate of `v`, 0 for each pinned one.
    fn free(&self, v: u32) -> DVec3 {
        match self.0.get(v as usize) {
            Some(p) => DVec3::from_array(p.map(|pinned| if pinned { 0.0 } else { 1.0 })),
            None => DVec3::ONE,
        }
    }
}

fn resolve_with(
    triangles: &[[u32; 3]],
    x0: &[DVec3],
    x1: &mut [DVec3],
    pins: Pins,
    params: &CollisionParams,
) -> Result<ResolveStats, Unresolved> {
    let fail = |cause| Err(Unresolved { cause });
    if x0.len() != x1.len() {
        return fail(UnresolvedCause::LengthMismatch {
            x0: x0.len(),
            x1: x1.len(),
        });
    }
    if let Some(vertex) = (0..x0.len()).find(|&i| !x0[i].is_finite() || !x1[i].is_finite()) {
        return fail(UnresolvedCause::NonFinite { vertex });
    }
    if let Some(triangle) = triangles
        .iter()
        .position(|t| !is_removed(t) && t.iter().any(|&v| v as usize >= x0.len()))
    {
        return fail(UnresolvedCause::BadTriangle { triangle });
    }
    let h = params.thickness.max(0.0);
    let mut stats = ResolveStats::default();
    let detector = Detector::new(triangles, x0.len());
    let detect = |x1: &[DVec3]| detector.detect(x0, x1);
    if h > 0.0 {
        let pairs = proximity_pairs(&detector, triangles, x0, h);
        stats.proximity_pairs = pairs.len();
        for c in &pairs {
            repel(triangles, c, x0, x1, h, pins);
        }
    }
    // After the first full detection, each round re-tests only pairs touching a vertex that
    // moved since the last detection or belonged to one of its contacts (every other pair
    // was found free and has not changed).
    let mut changed: Option<Vec<bool>> = None;
    let redetect = |x1: &[DVec3], changed: &Option<Vec<bool>>| match changed {
        None => detect(x1),
        Some(c) => detector.detect_changed(x0, x1, c),
    };
    let mark = |before: &[DVec3], after: &[DVec3], contacts: &[Contact]| {
        let mut c: Vec<bool> = before.iter().zip(after).map(|(p, q)| p != q).collect();
        for contact in contacts {
            for v in vertices_of(triangles, contact) {
                c[v as usize] = true;
            }
        }
        Some(c)
    };
    for _ in 0..params.impulse_iterations {
        let contacts = redetect(x1, &changed);
        stats.iterations += 1;
        if contacts.is_empty() {
            return Ok(stats);
        }
        stats.contacts += contacts.len();
        let before = x1.to_vec();
        for c in &contacts {
            impulse(triangles, c, x0, x1, h, pins);
        }
        changed = mark(&before, x1, &contacts);
    }
    let proposed: Vec<DVec3> = (0..x0.len()).map(|i| x1[i] - x0[i]).collect();
    let mut zones = Zones::new(x0.len());
    for _ in 0..params.zone_iterations {
        let contacts = redetect(x1, &changed);
        stats.iterations += 1;
        if contacts.is_empty() {
            stats.impact_zones = zones.count_nontrivial();
            return Ok(stats);
        }
        stats.contacts += contacts.len();
        for c in &contacts {
            let ids = vertices_of(triangles, c);
            for &v in &ids[1..] {
                zones.union(ids[0], v);
            }
        }
        let before = x1.to_vec();
        zones.translate(x0, x1, &proposed, params.pinned_zones_slide.then_some(pins));
        changed = mark(&before, x1, &contacts);
    }
    let contacts = detect(x1);
    stats.iterations += 1;
    stats.impact_zones = zones.count_nontrivial();
    if contacts.is_empty() {
        return Ok(stats);
    }
    fail(UnresolvedCause::ContactsRemain {
        contacts: contacts.len(),
        rounds: params.zone_iterations,
    })
}

/// The four vertices of a contact: `[vertex, a, b, c]` or `[a0, a1, b0, b1]`.
fn vertices_of(triangles: &[[u32; 3]], c: &Contact) -> [u32; 4] {
    match *c {
        Contact::VertexTriangle { vertex, triangle } => {
            let [a, b, c] = triangles[triangle as usize];
            [vertex, a, b, c]
        }
        Contact::EdgeEdge { a, b } => [a[0], a[1], b[0], b[1]],
    }
}

/// Weights of the four vertices in the relative position `Σ wᵢ xᵢ` of the two contact points
/// (vertex minus triangle point, or edge `a` point minus edge `b` point) at parameters `u, v`.
fn weights(c: &Contact, u: f64, v: f64) -> [f64; 4] {
    match c {
        Contact::VertexTriangle { .. } => {
            let (u, v) = (u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
            let s = (u + v).max(1.0);
            let (u, v) = (u / s, v / s);
            [1.0, -(1.0 - u - v), -u, -v]
        }
        Contact::EdgeEdge { .. } => {
            let (u, v) = (u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
            [1.0 - u, u, -(1.0 - v), -v]
        }
    }
}

fn combine(w: &[f64; 4], ids: &[u32; 4], x: &[DVec3]) -> DVec3 {
    (0..4).map(|i| w[i] * x[ids[i] as usize]).sum()
}

/// Adds the impulse that raises the relative displacement along `n` by `delta`, shared by the
/// four vertices in proportion to their weights (equal masses; Bridson et al. 2002 §7.1);
/// pinned coordinates take no share (their inverse mass is zero).
fn apply(ids: &[u32; 4], w: &[f64; 4], n: DVec3, delta: f64, x1: &mut [DVec3], pins: Pins) {
    let along = ids.map(|v| pins.free(v) * n);
    let norm: f64 = (0..4).map(|i| w[i] * w[i] * along[i].dot(n)).sum();
    if norm <= 0.0 || delta <= 0.0 {
        return;
    }
    for i in 0..4 {
        x1[ids[i] as usize] += (w[i] * delta / norm) * along[i];
    }
}

/// Proximity repulsion for a pair closer than `h` at the start (module doc, step 1).
fn repel(triangles: &[[u32; 3]], c: &Contact, x0: &[DVec3], x1: &mut [DVec3], h: f64, pins: Pins) {
    let ids = vertices_of(triangles, c);
    let p = ids.map(|i| x0[i as usize]);
    let w = match c {
        Contact::VertexTriangle { .. } => {
            let b = point_triangle_closest(p[0], p[1], p[2], p[3]);
            [1.0, -b[0], -b[1], -b[2]]
        }
        Contact::EdgeEdge { .. } => {
            let (s, t) = segment_segment_closest(p[0], p[1], p[2], p[3]);
            [1.0 - s, s, -(1.0 - t), -t]
        }
    };
    let gap = combine(&w, &ids, x0);
    let d0 = gap.length();
    if d0 <= 0.0 {
        return;
    }
    let n = gap / d0;
    let dn = (combine(&w, &ids, x1) - gap).dot(n);
    let allowed = if d0 >= 0.5 * h { 0.5 * h - d0 } else { 0.0 };
    apply(&ids, &w, n, allowed - dn, x1, pins);
}

/// CCD impulse for one contact (module doc, step 2); skipped if earlier impulses of the same
/// sweep already removed it.
fn impulse(
    triangles: &[[u32; 3]],
    c: &Contact,
    x0: &[DVec3],
    x1: &mut [DVec3],
    h: f64,
    pins: Pins,
) {
    let ids = vertices_of(triangles, c);
    let (p0, p1) = (ids.map(|i| x0[i as usize]), ids.map(|i| x1[i as usize]));
    let hit: Option<Hit> = match c {
        Contact::VertexTriangle { .. } => ccd::vertex_triangle_hit(&p0, &p1),
        Contact::EdgeEdge { .. } => ccd::edge_edge_hit(&p0, &p1),
    };
    let Some(hit) = hit else {
        return;
    };
    let w = weights(c, hit.u, hit.v);
    let at: [DVec3; 4] = std::array::from_fn(|i| p0[i] + hit.t * (p1[i] - p0[i]));
    let geometric = match c {
        Contact::VertexTriangle { .. } => (at[2] - at[1]).cross(at[3] - at[1]),
        Contact::EdgeEdge { .. } => (at[1] - at[0]).cross(at[3] - at[2]),
    };
    let gap0 = combine(&w, &ids, x0);
    let motion = combine(&w, &ids, x1) - gap0;
    // Normal: the geometric one when well defined, else the start offset, else against the
    // approach.
    let scale = (p0.iter().chain(p1.iter()))
        .map(|p| (*p - p0[0]).length_squared())
        .fold(0.0, f64::max);
    let n = if geometric.length_squared() > 1e-24 * scale * scale {
        geometric.normalize()
    } else if gap0.length_squared() > 0.0 {
        gap0.normalize()
    } else if motion.length_squared() > 0.0 {
        -motion.normalize()
    } else {
        return;
    };
    let n = within_free_plane(&ids, n, gap0, motion, pins).unwrap_or(n);
    let s0 = gap0.dot(n);
    let (n, s0) = if s0 < 0.0 { (-n, -s0) } else { (n, s0) };
    let target = 0.5 * s0.min(h);
    let end = s0 + motion.dot(n);
    apply(&ids, &w, n, target - end, x1, pins);
}

/// For a contact whose normal `n` no vertex may move along (all four hold that coordinate:
/// two primitives in one domain wall, sliding within it), the direction within the wall that
/// separates them: the start offset `gap0` without its part along `n`, else against the
/// approach `motion`. `None` when a vertex is free along `n` (the impulse acts as it is) or no
/// such direction exists. Along `n` the impulse did nothing, and every such contact went to
/// impact zones (the 24³ foam's late frames: a contact line running into a wall vertex, two
/// zones and 11 detection rounds in every substep).
fn within_free_plane(
    ids: &[u32; 4],
    n: DVec3,
    gap0: DVec3,
    motion: DVec3,
    pins: Pins,
) -> Option<DVec3> {
    if ids
        .iter()
        .any(|&v| (pins.free(v) * n).length_squared() > 0.0)
    {
        return None;
    }
    let across = |d: DVec3| (d - d.dot(n) * n).try_normalize();
    across(gap0).or_else(|| across(-motion))
}

/// Union–find over vertices for impact zones (smaller root index wins: deterministic).
struct Zones {
    parent: Vec<u32>,
}

impl Zones {
    fn new(n: usize) -> Self {
        Zones {
            parent: (0..n as u32).collect(),
        }
    }

    fn find(&mut self, mut v: u32) -> u32 {
        while self.parent[v as usize] != v {
            let g = self.parent[self.parent[v as usize] as usize];
            self.parent[v as usize] = g;
            v = g;
        }
        v
    }

    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        self.parent[hi as usize] = lo;
    }

    /// Moves every zone of two or more vertices by the mean of its members' proposed
    /// displacements (summed in vertex order). With `pins`, a coordinate any member has pinned
    /// moves by the mean of the pinned members' own displacements in it (zero where the
    /// tracker holds a vertex on its wall), so the zone slides along the wall; a common
    /// translation keeps the members still relative to each other either way.
    fn translate(
        &mut self,
        x0: &[DVec3],
        x1: &mut [DVec3],
        proposed: &[DVec3],
        pins: Option<Pins>,
    ) {
        let n = self.parent.len();
        let roots: Vec<u32> = (0..n as u32).map(|v| self.find(v)).collect();
        let mut sum = vec![DVec3::ZERO; n];
        let mut count = vec![0u32; n];
        let (mut held, mut holders) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
        for v in 0..n {
            let r = roots[v] as usize;
            sum[r] += proposed[v];
            count[r] += 1;
            if let Some(pins) = pins {
                let pinned = DVec3::ONE - pins.free(v as u32);
                held[r] += pinned * proposed[v];
                holders[r] += pinned;
            }
        }
        for v in 0..n {
            let r = roots[v] as usize;
            if count[r] > 1 {
                let mean = sum[r] / count[r] as f64;
                let d = DVec3::from_array(std::array::from_fn(|k| {
                    if holders[r][k] > 0.0 {
                        held[r][k] / holders[r][k]
                    } else {
                        mean[k]
                    }
                }));
                x1[v] = x0[v] + d;
            }
        }
    }

    fn count_nontrivial(&mut self) -> usize {
        let n = self.parent.len();
        let mut count = vec![0u32; n];
        for v in 0..n as u32 {
            count[self.find(v) as usize] += 1;
        }
        count.iter().filter(|&&c| c > 1).count()
    }
}

#[cfg(test)]
mod tests;
