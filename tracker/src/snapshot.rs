//! A tracker's whole state, as a checkpoint keeps it: restoring it continues the run bit for
//! bit. Each tracker that can be checkpointed has its own variant.

use crate::contour::MdTree;
use crate::front::front_tracker::FrontState;
use crate::mesh::LabeledMesh;

/// Everything a tracker needs to continue exactly where it stopped.
#[derive(Clone, Debug)]
pub enum TrackerSnapshot {
    /// The contouring tracker: its mesh, the tree that answers χ (and far φ) away from the
    /// interface, the volume-correction targets (per phase, and per component of the mesh)
    /// and each component's loss carried into the next step.
    Contour {
        mesh: LabeledMesh,
        tree: MdTree,
        volume_targets: Option<Vec<f64>>,
        component_targets: Vec<f64>,
        carried_loss: Vec<f64>,
    },
    /// The front tracker: its mesh, target edge length, domain box, flow substep count and
    /// the rest of [`FrontState`].
    Front(FrontState),
}

impl TrackerSnapshot {
    /// The interface mesh of the snapshot.
    pub fn mesh(&self) -> &LabeledMesh {
        match self {
            TrackerSnapshot::Contour { mesh, .. } => mesh,
            TrackerSnapshot::Front(state) => &state.mesh,
        }
    }
}
