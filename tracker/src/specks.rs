//! Removal of specks: components of a phase smaller than a tracker cell, which contouring
//! strands where a sheet thinner than a cell tears (the `enright` field stretches its sphere
//! into such sheets; issue 17). A speck is below what the grid resolves — its shape is a
//! contouring artefact — and far from its phase it sets the Hausdorff distance of the whole
//! run. The rule: a component (of a phase other than the background) with volume below the
//! bound whose interfaces all face one other phase becomes that phase — its interface faces go
//! and its faces on the domain boundary take the other phase — so the mesh stays closed and
//! label-consistent. The phase's volume is kept by the volume correction, whose targets never
//! counted the speck apart from its phase: a speck that splits off a component takes no share
//! of that component's target once it is gone, and its volume returns to the component.
//! Without the correction the speck's volume is lost (each at most the bound).

use polyphase_grid::{PhaseId, OUTSIDE};

use crate::mesh::LabeledMesh;
use crate::volume_correction::components::{Components, NONE};

/// Removes every speck of `mesh`, whose components ([`Components::find`] with `n_phases` and
/// `background`) are `components` — a component enclosing less than `max_volume`, all of whose
/// interfaces face one other phase and no other speck — and returns how many it removed and
/// the components of the mesh left (found again only when it changed). Vertices no triangle
/// uses any more are dropped.
pub fn remove_specks(
    mesh: &mut LabeledMesh,
    components: Components,
    n_phases: usize,
    background: PhaseId,
    max_volume: f64,
) -> (usize, Components) {
    let small: Vec<bool> = components.volume.iter().map(|&v| v < max_volume).collect();
    if !small.contains(&true) {
        return (0, components);
    }
    // Per small component, the one phase its interfaces face; `None` once a second appears.
    let mut facing: Vec<Option<Option<PhaseId>>> = vec![Some(None); components.len()];
    for (t, sides) in components.sides.iter().enumerate() {
        for (s, &c) in sides.iter().enumerate() {
            if c == NONE || !small[c as usize] {
                continue;
            }
            let other = mesh.labels[t][1 - s];
            if other == OUTSIDE {
                continue;
            }
            let entry = &mut facing[c as usize];
            // Two specks face to face: which would take the other's phase is moot; both stay.
            let across = sides[1 - s];
            if across != NONE && small[across as usize] {
                *entry = None;
            }
            match *entry {
                Some(None) => *entry = Some(Some(other)),
                Some(Some(p)) if p != other => *entry = None,
                _ => {}
            }
        }
    }
    let new_phase: Vec<Option<PhaseId>> = (0..components.len())
        .map(|c| facing[c].flatten().filter(|_| small[c]))
        .collect();
    let removed = new_phase.iter().filter(|p| p.is_some()).count();
    if removed == 0 {
        return (0, components);
    }
    let mut keep = Vec::with_capacity(mesh.triangle_count());
    for (t, sides) in components.sides.iter().enumerate() {
        let speck = sides.iter().enumerate().find_map(|(s, &c)| {
            let phase = if c == NONE {
                None
            } else {
                new_phase[c as usize]
            };
            phase.map(|p| (s, p))
        });
        match speck {
            None => keep.push(t),
            Some((s, phase)) => {
                // A face on the domain boundary is the speck's wall: it becomes the new phase's.
                if mesh.labels[t][1 - s] == OUTSIDE {
                    mesh.labels[t][s] = phase;
                    keep.push(t);
                }
            }
        }
    }
    retain_triangles(mesh, &keep);
    (removed, Components::find(mesh, n_phases, background))
}

/// Keeps the triangles `keep` (ascending) of `mesh` and the vertices they use, in order.
fn retain_triangles(mesh: &mut LabeledMesh, keep: &[usize]) {
    let mut index = vec![u32::MAX; mesh.vertices.len()];
    let mut vertices = Vec::new();
    let mut triangles = Vec::with_capacity(keep.len());
    let mut labels = Vec::with_capacity(keep.len());
    for &t in keep {
        let tri = mesh.triangles[t].map(|v| {
            let slot = &mut index[v as usize];
            if *slot == u32::MAX {
                *slot = vertices.len() as u32;
                vertices.push(mesh.vertices[v as usize]);
            }
            *slot
        });
        triangles.push(tri);
        labels.push(mesh.labels[t]);
    }
    *mesh = LabeledMesh {
        vertices,
        triangles,
        labels,
    };
}

#[cfg(test)]
mod tests;
