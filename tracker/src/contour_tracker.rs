//! The semi-Lagrangian contouring tracker of paper 004 (§3): each step backtraces every point
//! the adaptive tree needs through the velocity field, reads φ and χ exactly off the previous
//! mesh at the departure point, and contours the result into a new mesh. φ is then read
//! exactly off the new mesh where asked for, which replaces §6.4's redistancing
//! ([`ContourTracker::phi_chi`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseId, VelocityField};

use crate::contour::{MdTree, PhaseSampler};
use crate::mesh::LabeledMesh;
use crate::query::MeshQuery;
use crate::snapshot::TrackerSnapshot;
use crate::specks::remove_specks;
use crate::tracker::departure_point;
use crate::tracker::{InterfaceTracker, StepStats, TrackerError};
use crate::volume_correction::components::Components;
use crate::volume_correction::succession::{share_targets, Succession};
use crate::volume_correction::{
    carried_loss, first_aim, missed, reaim, VolumeShift, MAX_RETRIES, MISS_TOLERANCE,
};

/// Tracker state: the current mesh, its exact query structure and the tree it was contoured
/// from.
pub struct ContourTracker {
    grid: GridSpec,
    n_phases: usize,
    background: PhaseId,
    /// The tree as built: χ everywhere, φ as sampled while building.
    tree: MdTree,
    mesh: LabeledMesh,
    query: MeshQuery,
    /// Phase volumes each step's mesh is corrected back to; `None` turns the correction off.
    volume_targets: Option<Vec<f64>>,
    /// The current mesh's components (connected regions of a phase); empty while the
    /// correction is off.
    components: Components,
    /// Per component, the volume it is corrected back to; a phase's sum to its target.
    component_targets: Vec<f64>,
    /// Per component, the last step's loss beyond what its correction aimed for; the next step
    /// aims that much above the target (see [`crate::volume_correction::carried_loss`]).
    carried_loss: Vec<f64>,
    /// How a mesh's components are found: [`Components::find`] (a test swaps in the per-phase
    /// grouping to show what that did).
    regroup: fn(Components, usize) -> Components,
    /// How far (m) the interfaces may move in one step ([`ContourTracker::set_max_travel`]).
    max_travel: f64,
    /// Whether the volume correction moves faces near junctions less
    /// ([`ContourTracker::set_junction_weights`]).
    junction_weights: bool,
}

/// A step's default travel in cells, the scene format's default `time.cfl`: the
/// semi-Lagrangian step is stable for any, and each step resamples the mesh, so fewer, longer
/// steps keep more of it.
pub const DEFAULT_TRAVEL_CELLS: f64 = 8.0;

/// Components smaller than this many finest cells, facing one phase, are specks that each
/// step removes ([`remove_specks`]): below a cell the grid resolves no shape, only the
/// contouring's fragments of a torn sheet.
pub const SPECK_CELLS: f64 = 1.0;

/// How far (finest cells) [`ContourTracker::phi_chi`] reads φ exactly off the mesh: the band
/// §6.4's fast marching covered (the tree's unit cells reach about 6 cells from the
/// interface), and more than the solver reads exactly (face fractions and crossings between
/// cells of different phases, at most one solver cell away; solver cells are 1–4 tracker
/// cells in the built-in scenes).
pub const PHI_REACH_CELLS: f64 = 6.0;

impl ContourTracker {
    /// Builds the first mesh from exact initial φ, χ (paper 004 §7.2: "the tree was initially
    /// built with exact functions"). `background` is the phase everywhere when no interface exists.
    pub fn new(
        grid: GridSpec,
        initial: &dyn PhaseSampler,
        n_phases: usize,
        background: PhaseId,
    ) -> (ContourTracker, StepStats) {
        let (tree, mesh, query, stats, _) = rebuild(&grid, initial, background, None);
        let volume_targets = Some(mesh.phase_volumes(n_phases));
        let mut tracker = ContourTracker::assemble(grid, n_phases, background, tree, mesh, query);
        tracker.set_volume_targets(volume_targets);
        (tracker, stats)
    }

    /// A tracker over a built mesh and tree, without volume targets yet, travelling the default
    /// distance per step.
    fn assemble(
        grid: GridSpec,
        n_phases: usize,
        background: PhaseId,
        tree: MdTree,
        mesh: LabeledMesh,
        query: MeshQuery,
    ) -> ContourTracker {
        ContourTracker {
            grid,
            n_phases,
            background,
            tree,
            mesh,
            query,
            volume_targets: None,
            components: Components::default(),
            component_targets: Vec::new(),
            carried_loss: Vec::new(),
            regroup: |split, _| split,
            max_travel: DEFAULT_TRAVEL_CELLS * grid.h,
            junction_weights: false,
        }
    }

    /// A tracker from the saved state of another (a checkpoint): its mesh, its tree, the phases' volume targets, and its components' targets and carried loss
    /// ([`ContourTracker::component_targets`], [`ContourTracker::carried_loss`]). It continues
    /// exactly as the one they were taken from. Component state that does not fit the mesh's
    /// components (another count) is started afresh, as [`ContourTracker::set_volume_targets`]
    /// does.
    #[allow(clippy::too_many_arguments)]
    pub fn from_parts(
        grid: GridSpec,
        mesh: LabeledMesh,
        tree: MdTree,
        n_phases: usize,
        background: PhaseId,
        volume_targets: Option<Vec<f64>>,
        component_targets: Vec<f64>,
        carried_loss: Vec<f64>,
    ) -> ContourTracker {
        let query = MeshQuery::new(&mesh, background);
        let mut tracker = ContourTracker::assemble(grid, n_phases, background, tree, mesh, query);
        tracker.set_volume_targets(volume_targets);
        let n = tracker.components.len();
        if tracker.volume_targets.is_some()
            && component_targets.len() == n
            && carried_loss.len() == n
        {
            tracker.component_targets = component_targets;
            tracker.carried_loss = carried_loss;
        }
        tracker
    }

    /// Sets the per-phase volumes every step's mesh is corrected back to (see
    /// [`crate::volume_correction`]); `None` switches the correction off. By default the
    /// targets are the first mesh's volumes. Each phase's target is shared among its
    /// components by volume, and the carried loss starts again from zero.
    pub fn set_volume_targets(&mut self, targets: Option<Vec<f64>>) {
        self.components = match &targets {
            Some(_) => (self.regroup)(
                Components::find(&self.mesh, self.n_phases, self.background),
                self.n_phases,
            ),
            None => Components::default(),
        };
        let n = self.components.len();
        self.component_targets = match &targets {
            Some(phase_targets) => share_targets(&vec![None; n], &self.components, phase_targets),
            None => Vec::new(),
        };
        self.carried_loss = vec![0.0; n];
        self.volume_targets = targets;
    }

    /// Takes all components of a phase as one from now on: the per-phase correction that the
    /// per-component one replaced, for the tests that show the difference.
    #[cfg(test)]
    pub(crate) fn correct_whole_phases(&mut self) {
        self.regroup = Components::whole_phases;
        self.set_volume_targets(self.volume_targets.clone());
    }

    /// Switches the volume correction's junction weights on (off by default): faces within
    /// two cells of a junction then move less ([`crate::volume_correction::junction_weights`]).
    /// On for slabs, where a junction is a point of the plane: `vortex4`'s four-phase centre
    /// stays put (Hausdorff after a period at 256² 0.39–0.47 h with them, 0.54 h without). Off
    /// in 3D, where junctions are curves along whole stretched sheets and moving only the faces
    /// away from them tears the sheets: `enright` at 128³ after a period 23.3 h without them,
    /// 61.4 h with (40.6 h / 61.4 h without the speck removal), at 64³ 22.4 h / 27.6 h.
    pub fn set_junction_weights(&mut self, on: bool) {
        self.junction_weights = on;
    }

    /// Sets how far (m) the interfaces may move in one step (a scene's `time.cfl` cells);
    /// [`DEFAULT_TRAVEL_CELLS`] cells until then.
    pub fn set_max_travel(&mut self, travel: f64) {
        self.max_travel = travel;
    }

    /// The volumes the correction restores, if it is on.
    pub fn volume_targets(&self) -> Option<&[f64]> {
        self.volume_targets.as_deref()
    }

    /// The current mesh's components the correction keeps (empty while it is off).
    pub fn components(&self) -> &Components {
        &self.components
    }

    /// Per component, the volume the correction restores; part of the state a checkpoint
    /// saves.
    pub fn component_targets(&self) -> &[f64] {
        &self.component_targets
    }

    /// Per component, the last step's loss the next step adds to its target (empty when the
    /// correction is off); part of the state a checkpoint saves.
    pub fn carried_loss(&self) -> &[f64] {
        &self.carried_loss
    }

    /// The tracker's grid.
    pub fn grid(&self) -> &GridSpec {
        &self.grid
    }

    /// φ, χ at a point. χ from the tree where the point's leaf is uniform, else off the mesh:
    /// exact either way. φ off the mesh, exact, wherever an interface lies within
    /// [`PHI_REACH_CELLS`] cells; farther, the tree's interpolated φ but at least the reach
    /// (the build samples far nodes only that far: [`PhaseSampler::sample_near`]). This
    /// replaces paper 004 §6.4's fast marching outward from exact seeds (ARCHITECTURE.md
    /// "Departures from the original design"): every φ within the reach is exact, not first order, and no
    /// step pays for distances nobody reads (a 3D passive run reads none).
    pub fn phi_chi(&self, x: DVec3) -> (f64, PhaseId) {
        let Some((tree_phi, chi)) = self.tree.sample(x) else {
            let n = self.query.query(x);
            return (n.distance, n.phase);
        };
        let reach = PHI_REACH_CELLS * self.grid.h;
        let phi = self
            .query
            .query_within(x, reach)
            .map_or(tree_phi.max(reach), |n| n.distance);
        (phi, chi)
    }

    /// The exact query structure of the current mesh.
    pub fn query(&self) -> &MeshQuery {
        &self.query
    }
}

/// Build, contour, and the new mesh's query structure: paper 004 Table 1's stages, the query
/// in place of redistancing ([`ContourTracker::phi_chi`]). With `specks` (the phases' count),
/// the contoured mesh's components are found and its specks removed before the query is built
/// ([`remove_specks`], bound [`SPECK_CELLS`] cells, counted in the stats' events), and the
/// components of the mesh are returned for the volume correction.
fn rebuild(
    grid: &GridSpec,
    sampler: &dyn PhaseSampler,
    background: PhaseId,
    specks: Option<usize>,
) -> Built {
    let t0 = Instant::now();
    let tree = MdTree::build(grid, sampler);
    let t1 = Instant::now();
    let mut mesh = tree.contour(sampler);
    let t2 = Instant::now();
    let mut stages = vec![
        ("build", (t1 - t0).as_secs_f64()),
        ("contour", (t2 - t1).as_secs_f64()),
    ];
    let mut events = Vec::new();
    let components = specks.map(|n_phases| {
        let found = Components::find(&mesh, n_phases, background);
        stages.push(("components", t2.elapsed().as_secs_f64()));
        let started = Instant::now();
        let bound = SPECK_CELLS * grid.h.powi(3);
        let (removed, left) = remove_specks(&mut mesh, found, n_phases, background, bound);
        events.push(("specks_removed", removed));
        stages.push(("specks", started.elapsed().as_secs_f64()));
        left
    });
    let t3 = Instant::now();
    let query = MeshQuery::new(&mesh, background);
    stages.push(("query", t3.elapsed().as_secs_f64()));
    let stats = StepStats {
        stages,
        cells: tree.cell_count(),
        interface_cells: tree.interface_cell_count(),
        events,
        ..StepStats::default()
    };
    (tree, mesh, query, stats, components)
}

/// What [`rebuild`] makes: the tree, the mesh, its query, the step's stats and, when specks
/// were sought, the mesh's components.
type Built = (
    MdTree,
    LabeledMesh,
    MeshQuery,
    StepStats,
    Option<Components>,
);

/// Backtrace, then the exact query on the previous mesh (§3, §4).
struct Departure<'a> {
    previous: &'a MeshQuery,
    /// The tree the previous mesh was contoured from: χ far from it.
    previous_tree: &'a MdTree,
    /// Finest cell size of the previous tree.
    h: f64,
    velocity: &'a dyn VelocityField,
    lo: DVec3,
    hi: DVec3,
    t: f64,
    dt: f64,
    bad: &'a AtomicBool,
    /// Interface offsets of the volume correction, if it is on.
    shift: Option<VolumeShift>,
}

impl Departure<'_> {
    /// The departure point of `x`, clamped to the domain; `None` (and the step marked bad)
    /// where the velocity is not finite.
    fn origin(&self, x: DVec3) -> Option<DVec3> {
        let x0 = departure_point(self.velocity, x, self.t, self.dt);
        if !x0.is_finite() {
            self.bad.store(true, Ordering::Relaxed);
            return None;
        }
        Some(x0.clamp(self.lo, self.hi))
    }

    /// φ, χ of the previous (curved, shifted) mesh at `x0`, searched within `max_distance`.
    fn read(&self, x0: DVec3, max_distance: f64) -> Option<(f64, PhaseId)> {
        let shift = |t: usize| self.shift.as_ref().map_or(0.0, |s| s.shift(t));
        let n = self
            .previous
            .query_shifted_within(x0, max_distance, &shift)?;
        Some((n.distance, n.phase))
    }

    /// φ, χ with the unbounded search.
    fn read_all(&self, x0: DVec3) -> (f64, PhaseId) {
        let shift = |t: usize| self.shift.as_ref().map_or(0.0, |s| s.shift(t));
        let n = self.previous.query_shifted(x0, &shift);
        (n.distance, n.phase)
    }
}

/// How much farther than a flat triangle the curved, shifted interface of a contoured mesh
/// can lie, in finest cells: the Phong bulge is at most ½·sin 25°·√3 h ≈ 0.37 h (a contoured
/// triangle spans at most a cell's diagonal, and corners more than 25° off the facet do not
/// bulge) and the volume correction's shift at most ¼ h; one cell covers both.
const CURVED_MARGIN_CELLS: f64 = 1.0;

impl PhaseSampler for Departure<'_> {
    fn sample(&self, x: DVec3) -> (f64, PhaseId) {
        self.origin(x).map_or((0.0, 0), |x0| self.read_all(x0))
    }

    /// With no flat triangle of the previous mesh within `reach` plus the curved margin, the
    /// departure point lies in a leaf of the previous tree that no interface crosses (only
    /// mixed finest cells hold triangles, and every point of a mixed cell is within its
    /// diagonal of one), so that leaf's χ is the mesh's phase there and `reach` a lower bound.
    /// A mixed leaf without a triangle near (a removed speck's cells) takes the full search.
    fn sample_near(&self, x: DVec3, reach: f64) -> (f64, PhaseId) {
        let Some(x0) = self.origin(x) else {
            return (0.0, 0);
        };
        if let Some(near) = self.read(x0, reach + CURVED_MARGIN_CELLS * self.h) {
            return near;
        }
        match self.previous_tree.sample(x0) {
            Some((_, chi)) => (reach, chi),
            None => self.read_all(x0),
        }
    }
}

impl InterfaceTracker for ContourTracker {
    fn advance(
        &mut self,
        velocity: &dyn VelocityField,
        t: f64,
        dt: f64,
    ) -> Result<StepStats, TrackerError> {
        let bad = AtomicBool::new(false);
        let mut departure = Departure {
            previous: &self.query,
            previous_tree: &self.tree,
            h: self.grid.h,
            velocity,
            lo: self.grid.origin,
            hi: self.grid.upper(),
            t,
            dt,
            bad: &bad,
            shift: None,
        };
        let mut aim = self
            .volume_targets
            .as_ref()
            .map(|_| first_aim(&self.component_targets, &self.carried_loss));
        let (lo, hi) = (self.grid.origin, self.grid.upper());
        let back_to_departure = |x: DVec3| departure_point(velocity, x, t, dt).clamp(lo, hi);
        let mut more_stages: Vec<(&'static str, f64)> = Vec::new();
        let mut retries = 0;
        let ((tree, mesh, query, mut stats, _), next) = loop {
            // A quarter cell per step at most: a sheet lost in one step comes back over a few.
            departure.shift = aim.as_ref().map(|aim| {
                VolumeShift::new(
                    &self.mesh,
                    &self.components,
                    aim,
                    0.25 * self.grid.h,
                    if self.junction_weights {
                        self.grid.h
                    } else {
                        0.0
                    },
                )
            });
            let mut built = rebuild(&self.grid, &departure, self.background, Some(self.n_phases));
            if bad.load(Ordering::Relaxed) {
                let c = (self.grid.origin + self.grid.upper()) * 0.5;
                let x = first_non_finite(velocity, &self.grid, t, dt).unwrap_or(c);
                return Err(TrackerError::NonFiniteVelocity {
                    x: x.x,
                    y: x.y,
                    z: x.z,
                    t,
                });
            }
            let (Some(phase_targets), Some(shift), Some(aim)) =
                (&self.volume_targets, &departure.shift, &mut aim)
            else {
                break (built, None);
            };
            let split = built
                .4
                .take()
                .expect("rebuild with specks finds the components");
            let found = (self.regroup)(split, self.n_phases);
            let traced = Instant::now();
            let succession = Succession::trace(
                &self.mesh,
                &self.query,
                &self.components,
                &built.1,
                &found,
                &back_to_departure,
            );
            more_stages.push(("succession", traced.elapsed().as_secs_f64()));
            let targets = &self.component_targets;
            let after = succession.pull_back(&found.volume, targets);
            let cell = self.grid.h.powi(3);
            let floors: Vec<f64> = self
                .components
                .phase
                .iter()
                .map(|&p| {
                    let phase = phase_targets.get(p as usize).copied().unwrap_or(0.0);
                    (MISS_TOLERANCE * phase).max(cell)
                })
                .collect();
            if retries == MAX_RETRIES || !missed(shift.aimed(), &after, targets, &floors) {
                let carried = carried_loss(shift.aimed(), &after, targets);
                let inherited = succession.push_forward(targets, &found.volume);
                let next = (
                    share_targets(&inherited, &found, phase_targets),
                    succession
                        .push_forward(&carried, &found.volume)
                        .into_iter()
                        .map(|c| c.unwrap_or(0.0))
                        .collect(),
                    found,
                );
                break (built, Some(next));
            }
            reaim(aim, shift.aimed(), &after, targets);
            more_stages.extend(built.3.stages);
            retries += 1;
        };
        // The discarded tries' time counts in their stages, as does the correction's
        // bookkeeping (finding and tracing the components).
        for (name, secs) in more_stages {
            match stats.stages.iter_mut().find(|(n, _)| *n == name) {
                Some((_, total)) => *total += secs,
                None => stats.stages.push((name, secs)),
            }
        }
        if let Some(shift) = &departure.shift {
            let mut given = vec![0.0; self.n_phases];
            for (c, aimed) in shift.aimed().iter().enumerate() {
                if let (Some(a), Some(g)) =
                    (aimed, given.get_mut(self.components.phase[c] as usize))
                {
                    *g += a - self.components.volume[c];
                }
            }
            stats.volume_correction = given;
        }
        if let Some((targets, carried, components)) = next {
            self.component_targets = targets;
            self.carried_loss = carried;
            self.components = components;
        }
        self.tree = tree;
        self.mesh = mesh;
        self.query = query;
        Ok(stats)
    }

    fn max_travel(&self) -> f64 {
        self.max_travel
    }

    fn phi_chi(&self, x: DVec3) -> (f64, PhaseId) {
        ContourTracker::phi_chi(self, x)
    }

    fn mesh(&self) -> &LabeledMesh {
        &self.mesh
    }

    fn snapshot(&self) -> Option<TrackerSnapshot> {
        Some(TrackerSnapshot::Contour {
            mesh: self.mesh.clone(),
            tree: self.tree.clone(),
            volume_targets: self.volume_targets.clone(),
            component_targets: self.component_targets.clone(),
            carried_loss: self.carried_loss.clone(),
        })
    }

    fn phase_volumes(&self) -> Vec<f64> {
        self.mesh.phase_volumes(self.n_phases)
    }
}

/// A grid node where a backtrace is not finite, to name the place in the error.
fn first_non_finite(v: &dyn VelocityField, grid: &GridSpec, t: f64, dt: f64) -> Option<DVec3> {
    let [nx, ny, nz] = grid.dims;
    (0..=nz)
        .flat_map(|k| (0..=ny).flat_map(move |j| (0..=nx).map(move |i| (i, j, k))))
        .map(|(i, j, k)| grid.node(i, j, k))
        .find(|&x| !departure_point(v, x, t, dt).is_finite())
}

#[cfg(test)]
mod tests;
