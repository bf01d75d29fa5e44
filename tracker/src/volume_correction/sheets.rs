//! Faces of thin sheets take no offset: the volume a component loses where it is stretched
//! thinner than the grid resolves is given back on its thick parts.
//!
//! On `enright` at 128³ the blue liquid's sheet thins below a cell and tears; offsetting the
//! sheet's own faces while it is compressed thickens it, and the reversed flow stretches that
//! added thickness back by the compression's factor: the run ended with a 119-cell piece
//! reaching 23 h out. Held off the thin faces (their weight set to 0, so the Laplacian of
//! [`super::VolumeShift`] gives the whole deficit to the rest), the same run ends at 10.5 h with
//! every liquid within 0.05 % (README, "Full periods"). A component that is thin all over (a
//! torn piece of sheet) takes no offset either: given its loss back it is what grew the tendril.

use rayon::prelude::*;

use super::components::{Components, NONE};
use crate::mesh::LabeledMesh;
use crate::query::MeshQuery;
use polyphase_grid::OUTSIDE;

/// Sets to 0 the weight of every interface face of `mesh` on whose side a corrected component
/// is thinner than `2 · depth` there: the point `depth` in from the face's centroid along its
/// normal lies in another phase, or within `depth / 2` of an interface (`query` is `mesh`'s).
/// Each weight depends on its face alone, so any thread count gives the same bits.
pub fn hold_sheets(
    mesh: &LabeledMesh,
    components: &Components,
    corrected: &[bool],
    query: &MeshQuery,
    depth: f64,
    weights: &mut [f64],
) {
    weights.par_iter_mut().enumerate().for_each(|(t, w)| {
        if *w == 0.0 || mesh.labels[t].contains(&OUTSIDE) {
            return;
        }
        let [a, b, c] = mesh.corners(t);
        let centroid = (a + b + c) / 3.0;
        // The normal points into the front phase (side 0).
        let normal = mesh.normal(t);
        for (side, inward) in [(0, normal), (1, -normal)] {
            let comp = components.sides[t][side];
            if comp == NONE || !corrected[comp as usize] {
                continue;
            }
            let inside = query.query(centroid + inward * depth);
            if inside.phase != mesh.labels[t][side] || inside.distance < 0.5 * depth {
                *w = 0.0;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::fixtures::lattice_mesh;
    use crate::volume_correction::VolumeShift;

    /// A 3×3×3-cell block of phase 1 with a sheet one cell thick attached (6³ unit lattice,
    /// depth 0.75 cell): the sheet's faces are held, the middle of the block's top is not, and
    /// the block alone still gives the component its whole deficit.
    #[test]
    fn a_sheet_is_held_and_its_body_takes_the_deficit() {
        let block = |i, j, k| (1..4).contains(&i) && (1..4).contains(&j) && (1..4).contains(&k);
        let sheet = |i, j, k| (4..6).contains(&i) && (1..4).contains(&j) && k == 1;
        let mesh = lattice_mesh(6, |i, j, k| u16::from(block(i, j, k) || sheet(i, j, k)));
        let components = Components::find(&mesh, 2, 0);
        assert_eq!(components.len(), 1);
        let h = 1.0 / 6.0;
        let query = MeshQuery::new(&mesh, 0);
        let mut weights = vec![1.0; mesh.triangle_count()];
        hold_sheets(&mesh, &components, &[true], &query, 0.75 * h, &mut weights);
        let centroid = |t: usize| {
            let [a, b, c] = mesh.corners(t);
            (a + b + c) / 3.0
        };
        let on = |t: usize, z: f64, x: (f64, f64), y: (f64, f64)| {
            let p = centroid(t);
            !mesh.labels[t].contains(&OUTSIDE)
                && (p.z - z).abs() < 1e-12
                && (x.0..x.1).contains(&p.x)
                && (y.0..y.1).contains(&p.y)
        };
        let sheet_top: Vec<usize> = (0..mesh.triangle_count())
            .filter(|&t| on(t, 2.0 * h, (4.0 * h, 6.0 * h), (h, 4.0 * h)))
            .collect();
        let block_middle: Vec<usize> = (0..mesh.triangle_count())
            .filter(|&t| on(t, 4.0 * h, (2.0 * h, 3.0 * h), (2.0 * h, 3.0 * h)))
            .collect();
        assert_eq!((sheet_top.len(), block_middle.len()), (12, 2));
        assert!(sheet_top.iter().all(|&t| weights[t] == 0.0));
        assert!(block_middle.iter().all(|&t| weights[t] == 1.0));
        // The offsets solve one equation for the component over its unheld faces: its
        // first-order change is the deficit to rounding, with none of it on the sheet.
        let deficit = 1e-4;
        let target = components.volume[0] + deficit;
        let shift = VolumeShift::holding_sheets(
            &mesh,
            &components,
            &[target],
            1.0,
            0.0,
            (&query, 0.75 * h),
        );
        assert!(sheet_top.iter().all(|&t| shift.shift(t) == 0.0));
        let change: f64 = (0..mesh.triangle_count())
            .map(|t| {
                let a = mesh.area(t) * shift.shift(t);
                let [front, back] = components.sides[t];
                (if back == 0 { a } else { 0.0 }) - (if front == 0 { a } else { 0.0 })
            })
            .sum();
        assert!((change - deficit).abs() < 1e-15, "{change} vs {deficit}");
    }
}
