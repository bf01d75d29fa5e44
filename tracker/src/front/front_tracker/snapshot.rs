//! The front tracker's checkpoint state: everything a later step reads that the scene does not
//! give again (the scene gives the phases, the parameters and the mesh-driven flow).

use std::sync::OnceLock;

use glam::DVec3;
use polyphase_grid::PhaseId;

use super::{FrontError, FrontStepReport, FrontTracker};
use crate::front::connectivity::Connectivity;
use crate::front::params::FrontParams;
use crate::front::response::CollisionParams;
use crate::mesh::LabeledMesh;

/// A front tracker between two steps, as a checkpoint keeps it.
#[derive(Clone, Debug, PartialEq)]
pub struct FrontState {
    /// The mesh. Every step ends by compacting the connectivity, which rebuilds it from the
    /// mesh alone, so the mesh gives back the same incidence lists in the same order.
    pub mesh: LabeledMesh,
    /// Target edge length `L` in domain units (from the grid or the starting mesh).
    pub target: f64,
    /// Box of the domain boundary faces of the starting mesh, which constrains the motion.
    pub domain: Option<(DVec3, DVec3)>,
    /// Background volume of the boundary faces taken off the starting mesh.
    pub detached_volume: f64,
    /// Substeps of the mesh-driven flow so far (curl noise and normal flow alternate by it).
    pub flow_steps: u64,
    /// What the last step did ([`FrontTracker::last_report`]).
    pub report: FrontStepReport,
}

impl FrontTracker {
    /// The state a checkpoint keeps.
    pub fn state(&self) -> FrontState {
        FrontState {
            mesh: self.c.mesh.clone(),
            target: self.target,
            domain: self.domain,
            detached_volume: self.detached_volume,
            flow_steps: self.flow_steps,
            report: self.report,
        }
    }

    /// Continues from `state` with the scene's phases and parameters, exactly as the tracker
    /// that gave it would have; the scene's mesh-driven flow and volume correction are set
    /// again with [`FrontTracker::set_flow`] and [`FrontTracker::set_volume_correction`].
    /// Unlike [`FrontTracker::new`] it does not remesh.
    pub fn from_state(
        state: FrontState,
        n_phases: usize,
        background: PhaseId,
        mut params: FrontParams,
    ) -> Result<FrontTracker, FrontError> {
        params.validate().map_err(FrontError::InvalidParams)?;
        if !(state.target > 0.0 && state.target.is_finite()) {
            return Err(FrontError::InvalidParams(format!(
                "the saved target edge length {} is not positive",
                state.target
            )));
        }
        params.edge_length = Some(state.target);
        Ok(FrontTracker {
            c: Connectivity::new(state.mesh),
            n_phases,
            background,
            params,
            target: state.target,
            collision: CollisionParams::default(),
            domain: state.domain,
            query: OnceLock::new(),
            report: state.report,
            seconds: [0.0; 5],
            detached_volume: state.detached_volume,
            flow: None,
            flow_steps: state.flow_steps,
            gives_back: false,
        })
    }
}
