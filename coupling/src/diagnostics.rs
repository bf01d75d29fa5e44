//! Measurements of the interface for stats, as declared by the scene's `[[measure]]` tables:
//! fronts, tips, centroids, connected pieces of a phase, a slab's circularity and contact
//! angles.

use glam::DVec3;
use polyphase_scenes::MeasureKind;
use polyphase_tracker::{LabeledMesh, PhaseId, OUTSIDE};

use crate::contact_angle::contact_angles;

/// One measurement's value; `None` when the phase or interface is gone.
#[derive(Clone, Debug, PartialEq)]
pub enum Measured {
    /// A coordinate (front).
    Value(Option<f64>),
    /// Smallest and largest coordinate (tips).
    Range(Option<(f64, f64)>),
    /// A point (centroid).
    Point(Option<DVec3>),
    /// Connected pieces, in the order of their first triangle in the mesh.
    Pieces(Vec<Piece>),
    /// One angle (degrees) per phase asked for (contact angles).
    Angles(Option<[f64; 3]>),
}

/// One connected piece of a phase.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    /// Enclosed volume (m³).
    pub volume: f64,
    /// Centre of the enclosed volume.
    pub centroid: DVec3,
    /// Radius of the sphere of the same volume.
    pub radius: f64,
    /// Smallest vertex distance from the centroid over `radius` (1 for a sphere).
    pub nearest: f64,
    /// Largest vertex distance from the centroid over `radius` (1 for a sphere).
    pub farthest: f64,
}

/// Evaluates one measurement on the tracker's mesh. `rise_velocity`, `velocity_profile` and
/// `pressure_jump` need the fluid ([`crate::CoupledSim::rise_velocity`],
/// [`crate::CoupledSim::velocity_profile`], [`crate::CoupledSim::pressure_jump`]): here they
/// are `Value(None)`.
pub fn measure(mesh: &LabeledMesh, kind: &MeasureKind) -> Measured {
    match *kind {
        MeasureKind::Front { phase, axis } => {
            Measured::Value(interface_extent(mesh, phase, None, axis).map(|r| r.1))
        }
        MeasureKind::Tips { a, b, axis } => {
            Measured::Range(interface_extent(mesh, a, Some(b), axis))
        }
        MeasureKind::Centroid { phase } => {
            let all: Vec<usize> = (0..mesh.triangles.len())
                .filter(|&t| bounds(mesh, t, phase) != 0.0)
                .collect();
            let (volume, moment) = volume_moment(mesh, &all, phase);
            Measured::Point((volume > 0.0).then(|| moment / volume))
        }
        MeasureKind::Pieces { phase } => Measured::Pieces(pieces(mesh, phase)),
        MeasureKind::Circularity { phase, z } => Measured::Value(
            cross_section(mesh, phase, z)
                .filter(|s| s.area > 0.0 && s.perimeter > 0.0)
                .map(|s| 2.0 * (std::f64::consts::PI * s.area).sqrt() / s.perimeter),
        ),
        MeasureKind::ContactAngles { phases, reach } => {
            Measured::Angles(contact_angles(mesh, phases, reach))
        }
        MeasureKind::RiseVelocity { .. }
        | MeasureKind::VelocityProfile { .. }
        | MeasureKind::PressureJump { .. } => Measured::Value(None),
    }
}

/// The cut of a phase by a plane z = const.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrossSection {
    /// Area of the phase in the plane (m²).
    pub area: f64,
    /// Length of the cut through the phase's interfaces with other phases (m); the domain's
    /// walls, where the phase touches them, are not counted.
    pub perimeter: f64,
}

/// The cross-section of `phase` in the plane z = `z`: each triangle bounding the phase that
/// straddles the plane contributes the segment where the plane cuts it. A vertex counts as
/// above the plane when z_v ≥ z, so a vertex or edge lying in the plane is cut once, by the
/// triangles that reach below it. The area is the shoelace sum over the segments, each
/// oriented by its triangle's normal so the phase lies to its left (domain faces included,
/// which closes a section that touches a wall); the perimeter sums the segments of
/// interfaces with other phases only. `None` when the plane misses the phase.
pub fn cross_section(mesh: &LabeledMesh, phase: PhaseId, z: f64) -> Option<CrossSection> {
    let (mut twice_area, mut perimeter, mut cut) = (0.0, 0.0, false);
    for (t, labels) in mesh.labels.iter().enumerate() {
        let side = bounds(mesh, t, phase);
        if side == 0.0 {
            continue;
        }
        let corners = mesh.corners(t);
        let above = corners.map(|c| c.z >= z);
        let mut ends = [DVec3::ZERO; 2];
        let mut n = 0;
        for i in 0..3 {
            let (a, b) = (corners[i], corners[(i + 1) % 3]);
            if above[i] != above[(i + 1) % 3] {
                ends[n.min(1)] = a + (b - a) * ((z - a.z) / (b.z - a.z));
                n += 1;
            }
        }
        if n != 2 {
            continue;
        }
        cut = true;
        // The phase's outward normal in the plane; the segment runs with the phase on its
        // left, i.e. the outward normal on its right: (d.y, −d.x) · n > 0.
        let [a, b, c] = corners;
        let outward = side * (b - a).cross(c - a);
        let (mut p, mut q) = (ends[0], ends[1]);
        let d = q - p;
        if d.y * outward.x - d.x * outward.y < 0.0 {
            std::mem::swap(&mut p, &mut q);
        }
        twice_area += p.x * q.y - q.x * p.y;
        if !labels.contains(&OUTSIDE) {
            perimeter += d.truncate().length();
        }
    }
    cut.then_some(CrossSection {
        area: 0.5 * twice_area,
        perimeter,
    })
}

/// +1 when triangle `t` bounds `phase` from its back side, −1 from its front side, 0 when it
/// does not separate `phase` from anything else.
fn bounds(mesh: &LabeledMesh, t: usize, phase: PhaseId) -> f64 {
    let [front, back] = mesh.labels[t];
    if front == back {
        0.0
    } else if back == phase {
        1.0
    } else if front == phase {
        -1.0
    } else {
        0.0
    }
}

/// Volume and first moment ∫x dV of the region of `phase` bounded by `triangles` (divergence
/// theorem over tetrahedra from the first corner, which keeps the products small).
fn volume_moment(mesh: &LabeledMesh, triangles: &[usize], phase: PhaseId) -> (f64, DVec3) {
    let Some(&first) = triangles.first() else {
        return (0.0, DVec3::ZERO);
    };
    let origin = mesh.corners(first)[0];
    let (mut volume, mut moment) = (0.0, DVec3::ZERO);
    for &t in triangles {
        let [a, b, c] = mesh.corners(t);
        let (a, b, c) = (a - origin, b - origin, c - origin);
        let v = bounds(mesh, t, phase) * a.dot(b.cross(c)) / 6.0;
        volume += v;
        moment += v * (a + b + c) / 4.0;
    }
    (volume, moment + volume * origin)
}

/// The connected pieces of `phase`: its boundary triangles grouped by shared vertices.
pub fn pieces(mesh: &LabeledMesh, phase: PhaseId) -> Vec<Piece> {
    let mut parent: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let up = parent[parent[v as usize] as usize];
            parent[v as usize] = up;
            v = up;
        }
        v
    }
    let boundary: Vec<usize> = (0..mesh.triangles.len())
        .filter(|&t| bounds(mesh, t, phase) != 0.0 && mesh.labels[t] != [OUTSIDE, OUTSIDE])
        .collect();
    for &t in &boundary {
        let [a, b, c] = mesh.triangles[t];
        for (x, y) in [(a, b), (b, c)] {
            let (rx, ry) = (root(&mut parent, x), root(&mut parent, y));
            if rx != ry {
                parent[rx.max(ry) as usize] = rx.min(ry);
            }
        }
    }
    let mut groups: Vec<(u32, Vec<usize>)> = Vec::new();
    for &t in &boundary {
        let r = root(&mut parent, mesh.triangles[t][0]);
        match groups.iter_mut().find(|(g, _)| *g == r) {
            Some((_, list)) => list.push(t),
            None => groups.push((r, vec![t])),
        }
    }
    groups
        .iter()
        .map(|(_, triangles)| {
            let (volume, moment) = volume_moment(mesh, triangles, phase);
            let centroid = moment / volume;
            let radius = (3.0 * volume.abs() / (4.0 * std::f64::consts::PI)).cbrt();
            let (mut nearest, mut farthest) = (f64::INFINITY, 0.0f64);
            for &t in triangles {
                for &v in &mesh.triangles[t] {
                    let d = mesh.vertices[v as usize].distance(centroid);
                    nearest = nearest.min(d);
                    farthest = farthest.max(d);
                }
            }
            Piece {
                volume,
                centroid,
                radius,
                nearest: nearest / radius,
                farthest: farthest / radius,
            }
        })
        .collect()
}

/// (min, max) along `axis` of the vertices of triangles separating phase `a` from `b`
/// (`b = None`: from any other phase, domain boundary included); `None` when there are none.
/// The surge front of a dam break is the max x of the liquid's surface; the bubble and spike
/// tips of Rayleigh–Taylor are the max and min y of the heavy–light interface.
pub fn interface_extent(
    mesh: &LabeledMesh,
    a: PhaseId,
    b: Option<PhaseId>,
    axis: usize,
) -> Option<(f64, f64)> {
    let mut range: Option<(f64, f64)> = None;
    for (tri, labels) in mesh.triangles.iter().zip(&mesh.labels) {
        let hit = match b {
            Some(b) => *labels == [a, b] || *labels == [b, a],
            None => labels.contains(&a) && labels[0] != labels[1],
        };
        if !hit {
            continue;
        }
        for &v in tri {
            let c = mesh.vertices[v as usize][axis];
            range = Some(match range {
                Some((lo, hi)) => (lo.min(c), hi.max(c)),
                None => (c, c),
            });
        }
    }
    range
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use polyphase_tracker::OUTSIDE;

    #[test]
    fn extent_selects_triangles_by_label_pair() {
        let mesh = LabeledMesh {
            vertices: vec![
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(1.0, 0.5, 0.0),
                DVec3::new(0.0, 1.0, 0.0),
                DVec3::new(3.0, -2.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 3, 2]],
            labels: vec![[1, 0], [1, OUTSIDE]],
        };
        assert_eq!(interface_extent(&mesh, 0, Some(1), 0), Some((0.0, 1.0)));
        assert_eq!(interface_extent(&mesh, 1, None, 1), Some((-2.0, 1.0)));
        assert_eq!(interface_extent(&mesh, 2, None, 1), None);
    }

    /// An octahedron with vertices at distance `r` from `centre`, labeled [outside, inside].
    fn octahedron(centre: DVec3, r: f64, inside: PhaseId, outside: PhaseId) -> LabeledMesh {
        let vertices = [
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
        ]
        .map(|d| centre + r * d)
        .to_vec();
        let mut triangles = Vec::new();
        for (x, y, z) in [
            (0, 2, 4),
            (2, 1, 4),
            (1, 3, 4),
            (3, 0, 4),
            (2, 0, 5),
            (1, 2, 5),
            (3, 1, 5),
            (0, 3, 5),
        ] {
            triangles.push([x, y, z]);
        }
        let n = triangles.len();
        LabeledMesh {
            vertices,
            triangles,
            labels: vec![[outside, inside]; n],
        }
    }

    #[test]
    fn pieces_are_found_with_their_volume_and_roundness() {
        // Two octahedra of water (phase 1) in air (phase 0): each encloses (4/3) r³, and its
        // vertices lie at r from the centroid, over the equivalent radius (1/π)^(1/3) r.
        let mut mesh = octahedron(DVec3::new(1.0, 2.0, 3.0), 0.5, 1, 0);
        mesh.append(&octahedron(DVec3::new(-1.0, 0.0, 0.0), 0.25, 1, 0));
        let found = pieces(&mesh, 1);
        assert_eq!(found.len(), 2);
        let ratio = std::f64::consts::PI.cbrt();
        for (p, (c, r)) in found.iter().zip([
            (DVec3::new(1.0, 2.0, 3.0), 0.5),
            (DVec3::new(-1.0, 0.0, 0.0), 0.25),
        ]) {
            assert!((p.volume - 4.0 / 3.0 * r * r * r).abs() < 1e-12, "{p:?}");
            assert!(p.centroid.distance(c) < 1e-12, "{p:?}");
            assert!((p.farthest - ratio).abs() < 1e-12 && (p.nearest - ratio).abs() < 1e-12);
        }
        // The air around them is one region with negative enclosed volume seen from inside.
        assert!(pieces(&mesh, 2).is_empty());
        match measure(&mesh, &MeasureKind::Centroid { phase: 1 }) {
            Measured::Point(Some(c)) => {
                // Volume-weighted: 8 : 1 between the two.
                let expected = (8.0 * DVec3::new(1.0, 2.0, 3.0) + DVec3::new(-1.0, 0.0, 0.0)) / 9.0;
                assert!(c.distance(expected) < 1e-12, "{c}");
            }
            other => panic!("{other:?}"),
        }
    }

    /// A prism of phase 1 in phase 0 over the polygon `corners` (counter-clockwise), from
    /// z = 0 to 2 with a ring of vertices at z = 1 as well; its caps face the domain
    /// (`OUTSIDE`), and so do the sides listed in `on_wall`.
    fn prism(corners: &[(f64, f64)], on_wall: &[usize]) -> LabeledMesh {
        let n = corners.len() as u32;
        let mut mesh = LabeledMesh {
            vertices: Vec::new(),
            triangles: Vec::new(),
            labels: Vec::new(),
        };
        for z in [0.0, 1.0, 2.0] {
            for &(x, y) in corners {
                mesh.vertices.push(DVec3::new(x, y, z));
            }
        }
        for layer in 0..2 {
            for i in 0..n {
                let j = (i + 1) % n;
                let (a, b) = (layer * n + i, layer * n + j);
                let (c, d) = (a + n, b + n);
                let outer = if on_wall.contains(&(i as usize)) {
                    OUTSIDE
                } else {
                    0
                };
                mesh.triangles.push([a, b, d]);
                mesh.triangles.push([a, d, c]);
                mesh.labels.extend([[outer, 1], [outer, 1]]);
            }
        }
        for i in 1..n - 1 {
            mesh.triangles.push([0, i + 1, i]);
            mesh.triangles.push([2 * n, 2 * n + i, 2 * n + i + 1]);
            mesh.labels.extend([[OUTSIDE, 1], [OUTSIDE, 1]]);
        }
        mesh
    }

    #[test]
    fn a_cross_section_has_the_polygons_area_and_perimeter() {
        // A regular 12-gon of circumradius r: area 3 r², perimeter 24 r sin(π/12). Cut between
        // the rings and exactly through the middle ring alike.
        let r = 0.3;
        let corners: Vec<(f64, f64)> = (0..12)
            .map(|k| {
                let a = std::f64::consts::PI * k as f64 / 6.0;
                (0.5 + r * a.cos(), 1.0 + r * a.sin())
            })
            .collect();
        let mesh = prism(&corners, &[]);
        let perimeter = 24.0 * r * (std::f64::consts::PI / 12.0).sin();
        for z in [0.5, 1.0, 1.5] {
            let s = cross_section(&mesh, 1, z).unwrap();
            assert!((s.area - 3.0 * r * r).abs() < 1e-12, "{z}: {s:?}");
            assert!((s.perimeter - perimeter).abs() < 1e-12, "{z}: {s:?}");
            let Measured::Value(Some(c)) =
                measure(&mesh, &MeasureKind::Circularity { phase: 1, z })
            else {
                panic!("no circularity at {z}");
            };
            let exact = 2.0 * (std::f64::consts::PI * 3.0).sqrt() * r / perimeter;
            assert!((c - exact).abs() < 1e-12, "{c} against {exact}");
        }
        // The phase around it sees the same section with the opposite sign, and a plane
        // above the prism misses it.
        assert!((cross_section(&mesh, 0, 1.0).unwrap().area + 3.0 * r * r).abs() < 1e-12);
        assert_eq!(cross_section(&mesh, 1, 2.5), None);
        assert_eq!(
            measure(&mesh, &MeasureKind::Circularity { phase: 1, z: 2.5 }),
            Measured::Value(None)
        );
    }

    #[test]
    fn a_wall_closes_the_section_but_is_no_perimeter() {
        // A unit square against a wall along its first side: area 1, perimeter 3.
        let mesh = prism(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)], &[0]);
        let s = cross_section(&mesh, 1, 0.25).unwrap();
        assert!(
            (s.area - 1.0).abs() < 1e-12 && (s.perimeter - 3.0).abs() < 1e-12,
            "{s:?}"
        );
    }
}
