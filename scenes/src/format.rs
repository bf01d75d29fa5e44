//! The scene file as written by users (TOML, serde). Every optional field has a default, and
//! the resolved scene (defaults filled in) serialises back to the same format.

use std::collections::BTreeMap;
use std::fmt;

use polyphase_tracker::front::params::FrontParams;
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

/// A whole scene file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Short name, used for the default output folder.
    pub name: String,
    /// One line shown by `polyphase scenes`.
    #[serde(default)]
    pub description: String,
    /// Which interface tracker runs the scene, and its parameters.
    #[serde(default)]
    pub tracker: TrackerSpec,
    /// Whether each tracker step gives every phase back its exact initial volume by a small
    /// offset of the interfaces (`polyphase_tracker::volume_correction`; not in paper 004).
    /// The front tracker gives back only what its mesh operations changed in a velocity field
    /// (merging, remeshing, T1/T2; `front_tracker/give_back.rs`) in steps that change the
    /// topology, not the motion's error.
    #[serde(default = "default_true")]
    pub volume_correction: bool,
    /// Tracker cells along the longest domain axis.
    pub resolution: i64,
    pub domain: DomainSpec,
    pub time: TimeSpec,
    pub velocity: VelocitySpec,
    /// Fluid solver settings of a coupled scene (`velocity = { field = "fluid" }`); filled with
    /// defaults there, and an error on a passive scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<SolverSpec>,
    /// Name of the phase that fills every point no shape covers.
    pub background: String,
    /// With `[foam]`, empty (cells `cell1`…`cellN` are generated) or one phase per cell.
    #[serde(default)]
    pub phases: Vec<PhaseSpec>,
    /// A Voronoi foam filling the domain, one phase per cell, instead of `shapes`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub foam: Option<FoamSpec>,
    /// Initial shapes. Where shapes overlap, the one with the higher `priority` wins; shapes of
    /// different phases with the same priority must not overlap (the scene would be ambiguous).
    #[serde(default)]
    pub shapes: Vec<ShapeSpec>,
    /// Optional hints for the offline renderer (`render/`); absent fields use its defaults.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub render: Option<RenderHints>,
    /// Measurements of the interface written to `stats.jsonl` every frame (`[[measure]]`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub measure: Vec<MeasureSpec>,
    /// Surface tension per pair of phases (`[[tension]]`); pairs not listed have none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tension: Vec<TensionSpec>,
}

/// The surface tension between two phases: `phases = ["water", "air"], sigma = 0.0728`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TensionSpec {
    /// The two phases the interface separates, by name.
    pub phases: [String; 2],
    /// Surface tension coefficient σ (N/m), ≥ 0.
    pub sigma: f64,
}

/// One measurement as written: `kind` selects which of the optional fields are required.
/// `front` (phase, axis): the largest coordinate along `axis` of the phase's surface; `tips`
/// (phases = [a, b], axis): the smallest and largest coordinate of the a–b interface;
/// `centroid` (phase): the centre of the phase's volume; `pieces` (phase): every connected
/// piece of the phase with its volume, centroid and roundness; `rise_velocity` (phase, coupled
/// scenes): the mean velocity of the phase's solver cells against gravity; `velocity_profile`
/// (component, axis, coupled scenes): the fluid's velocity component along each layer of
/// solver cells across `axis` (a shear flow's profile); `pressure_jump` (phases = [inside,
/// outside], coupled scenes): the mean pressure of the inside phase's solver cells minus the
/// outside phase's (a static drop's Laplace jump); `circularity` (phase, slab scenes): the
/// perimeter of the circle of the phase's cross-sectional area over the perimeter of its
/// interfaces, cut at the slab's mid-plane; `contact_angles` (phases = [a, b, c]): the angle
/// of each phase's wedge where the three meet, averaged along their triple curves.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasureSpec {
    pub kind: String,
    /// Key in `stats.jsonl`; default `<kind>_<phases>[_<axis>]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phase: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phases: Option<Vec<String>>,
    /// `x`, `y` or `z`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<String>,
    /// `velocity_profile` only: the velocity component, `x`, `y` or `z`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub component: Option<String>,
}

/// Render hints read by the Mitsuba pipeline; every field optional.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderHints {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_origin: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera_target: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<[f64; 3]>,
    /// Horizontal field of view, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fov: Option<f64>,
    /// Phases drawn as rough plastic instead of dielectric liquid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub opaque: Option<Vec<String>>,
    /// Draw the domain walls as thin glass.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tank: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground: Option<bool>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smooth: Option<bool>,
    /// Distance (m) over which a liquid's transmittance equals its colour.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub absorption_length: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ambient: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub light: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fps: Option<u32>,
    /// Cut-away view: triangles on the side `normal` points to are not drawn, and opaque
    /// surfaces show both sides, so shells open toward the camera (paper 000 Figs. 23, 24).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cutaway: Option<HalfSpaceSpec>,
}

/// The tracker of a scene: `tracker = "front"` (a kind alone), or a `[tracker]` table with
/// `kind` and, for the front tracker, `[tracker.front]` parameters (documented on
/// [`FrontParams`]; absent keys keep their defaults). The resolved scene always has the table.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct TrackerSpec {
    pub kind: TrackerKind,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub front: Option<FrontParams>,
}

/// The `[tracker]` table form of [`TrackerSpec`].
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TrackerTable {
    #[serde(default)]
    kind: TrackerKind,
    front: Option<FrontParams>,
}

impl<'de> Deserialize<'de> for TrackerSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Either;
        impl<'de> Visitor<'de> for Either {
            type Value = TrackerSpec;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("\"contour\", \"front\" or a [tracker] table")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<TrackerSpec, E> {
                let kind = TrackerKind::deserialize(de::value::StrDeserializer::<E>::new(v))?;
                Ok(TrackerSpec { kind, front: None })
            }
            fn visit_map<M: MapAccess<'de>>(self, m: M) -> Result<TrackerSpec, M::Error> {
                let t = TrackerTable::deserialize(de::value::MapAccessDeserializer::new(m))?;
                Ok(TrackerSpec {
                    kind: t.kind,
                    front: t.front,
                })
            }
        }
        d.deserialize_any(Either)
    }
}

/// The interface tracker a scene runs with (ARCHITECTURE.md "The tracker contract").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TrackerKind {
    /// Semi-Lagrangian contouring (paper 004).
    #[default]
    Contour,
    /// Explicit front tracking (paper 000).
    Front,
}

impl std::str::FromStr for TrackerKind {
    type Err = String;

    /// `contour` or `front`, as in scene files.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "contour" => Ok(TrackerKind::Contour),
            "front" => Ok(TrackerKind::Front),
            _ => Err(format!("unknown tracker '{s}' (trackers: contour, front)")),
        }
    }
}

/// The simulation box.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainSpec {
    pub lo: [f64; 3],
    pub hi: [f64; 3],
    /// A 2D test run as a thin 3D slab: the z extent becomes exactly two cells.
    #[serde(default)]
    pub slab: bool,
}

/// Duration and output rate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSpec {
    /// Simulated seconds.
    pub end: f64,
    /// Frames written after the initial one (frame 0 is the initial state).
    pub frames: i64,
    /// Largest tracker step as a multiple of h / (max speed). Semi-Lagrangian steps are stable
    /// for any value, and every step resamples the mesh, which costs O((h/R)²) of a region's
    /// volume; with the RK4 backtrace of smooth analytic flows, fewer and larger steps are the
    /// more accurate choice (measured: a ball turned once at 64³ drifts 4.2 % at cfl 2,
    /// 1.3 % at cfl 8).
    #[serde(default = "default_cfl")]
    pub cfl: f64,
    /// The flow returns every shape to its start at `end` (volume and Hausdorff error reported).
    #[serde(default)]
    pub periodic: bool,
}

fn default_cfl() -> f64 {
    8.0
}

/// An analytic velocity field for passive advection.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "field", rename_all = "snake_case", deny_unknown_fields)]
pub enum VelocitySpec {
    /// No motion.
    Still,
    /// Rigid rotation about the axis through `center` parallel to +z.
    Rotation {
        center: [f64; 3],
        /// rad/s, counter-clockwise seen from +z.
        angular_velocity: f64,
    },
    /// Enright et al. 2002 deformation field on the unit cube, reversing at half `period`.
    Enright { period: f64 },
    /// Single-vortex stretching field on the unit square (paper 004 Eq. 2), w = 0.
    Vortex { period: f64 },
    /// The velocity of the MAC-grid fluid solver, coupled to the tracker (paper 004 §7.5).
    Fluid,
    /// Constant-speed normal flow per pair of phases with area-weighted vertex normals
    /// (paper 000 §8.2–8.3); front tracker only. From `reverse_at` seconds on (if given) every
    /// speed changes sign.
    Normal {
        speeds: Vec<PairSpeedSpec>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        reverse_at: Option<f64>,
    },
    /// The same flow by face offsetting (Jiao 2007; paper 000 §8.2's flows); front tracker
    /// only; `reverse_at` as for `normal`.
    NormalFom {
        speeds: Vec<PairSpeedSpec>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        reverse_at: Option<f64>,
    },
    /// Mean-curvature flow (paper 000 §8.4) at `rate` m²/s (default 1); front tracker only.
    MeanCurvature {
        #[serde(default = "default_rate")]
        rate: f64,
    },
    /// Curl noise alternating with normal flow, step by step (paper 000 §8.1, Fig. 21); front
    /// tracker only.
    CurlNoise {
        /// Peak speed of the noise (m/s).
        amplitude: f64,
        /// Wavelength of the noise (m).
        scale: f64,
        /// Seed of the noise's modes.
        #[serde(default)]
        seed: u64,
        speeds: Vec<PairSpeedSpec>,
    },
}

fn default_rate() -> f64 {
    1.0
}

/// `{ from = "red", into = "air", speed = 0.1 }`: the interface between two phases moves
/// along its normal from `from` into `into` at `speed` m/s (negative: the other way).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairSpeedSpec {
    pub from: String,
    pub into: String,
    pub speed: f64,
}

/// Solver settings of a coupled scene; every field has a default.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Solver cells along the longest domain axis; the tracker's `resolution` must be a whole
    /// multiple of it (the tracker runs finer, ARCHITECTURE.md "PhaseField"). Default: half the
    /// tracker's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution: Option<i64>,
    /// m/s²; −y by convention (ARCHITECTURE.md "Conventions").
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    /// Largest step as a fraction of h / (max speed) (solver CFL number).
    #[serde(default = "default_solver_cfl")]
    pub cfl: f64,
    /// Largest step in seconds, whatever the speed. Default: no limit beyond the frame.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_dt: Option<f64>,
    /// Relative residual at which the pressure and viscosity solves stop.
    #[serde(default = "default_tolerance")]
    pub tolerance: f64,
    /// Preconditioner of both the pressure and the viscosity solve. Default: multigrid for
    /// pressure (7 CG iterations a step against MIC(0)'s 53 on `dambreak_column` at 128×64,
    /// 2.3× less time), MIC(0) for viscosity (its solves take one or two iterations there,
    /// where multigrid's set-up costs more than it saves).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preconditioner: Option<PreconditionerSpec>,
    /// Walls of the solver's box (`[solver.boundary]`); every wall free-slip by default.
    #[serde(default, skip_serializing_if = "BoundarySpec::is_default")]
    pub boundary: BoundarySpec,
}

/// The solver's boundary per axis and the velocities of moving walls: what sets up shear
/// flows such as Couette (a moving no-slip wall) and Poiseuille (no-slip walls, a periodic
/// channel driven by `gravity`). The tracker does not wrap: a periodic axis suits interfaces
/// that meet its ends unchanged (layers along it), not shapes crossing them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    #[serde(default)]
    pub x: BoundaryKind,
    #[serde(default)]
    pub y: BoundaryKind,
    #[serde(default)]
    pub z: BoundaryKind,
    /// Velocity (m/s) of a moving no-slip wall, by wall name (`x_low`, `x_high`, `y_low`,
    /// `y_high`, `z_low`, `z_high`); tangential, as walls do not move along their normal.
    /// Walls not named are at rest.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub wall_velocity: BTreeMap<String, [f64; 3]>,
}

/// Names of the six walls, `wall_velocity`'s keys, in the order axis × (low, high).
pub const WALLS: [&str; 6] = ["x_low", "x_high", "y_low", "y_high", "z_low", "z_high"];

impl BoundarySpec {
    /// The kinds of the x, y and z axes.
    pub fn axes(&self) -> [BoundaryKind; 3] {
        [self.x, self.y, self.z]
    }

    fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

/// Boundary condition of one axis of the solver's box.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoundaryKind {
    /// Walls at both ends, no normal flow, no tangential stress.
    #[default]
    FreeSlip,
    /// Walls at both ends that hold the fluid at their own velocity (`wall_velocity`).
    NoSlip,
    /// The box repeats along the axis.
    Periodic,
}

impl BoundaryKind {
    /// The name as scene files write it.
    pub fn name(self) -> &'static str {
        match self {
            BoundaryKind::FreeSlip => "free_slip",
            BoundaryKind::NoSlip => "no_slip",
            BoundaryKind::Periodic => "periodic",
        }
    }
}

impl Default for SolverSpec {
    fn default() -> Self {
        Self {
            resolution: None,
            gravity: default_gravity(),
            cfl: default_solver_cfl(),
            max_dt: None,
            tolerance: default_tolerance(),
            preconditioner: None,
            boundary: BoundarySpec::default(),
        }
    }
}

/// Preconditioner named in a scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PreconditionerSpec {
    /// Modified incomplete Cholesky.
    Mic0,
    /// Geometric multigrid V-cycle.
    Multigrid,
}

fn default_gravity() -> [f64; 3] {
    [0.0, -9.81, 0.0]
}
fn default_solver_cfl() -> f64 {
    1.0
}
fn default_tolerance() -> f64 {
    1e-6
}

/// A Voronoi foam: `regions` seeds placed uniformly at random (from `seed`) in the domain,
/// each filling its Voronoi cell with its own phase (paper 000 Fig. 24).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FoamSpec {
    /// Number of cells, at least 2.
    pub regions: i64,
    /// Seed of the seeds' random placement (the same seed gives the same foam).
    #[serde(default)]
    pub seed: u64,
}

/// A phase: physical properties and render hints.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseSpec {
    pub name: String,
    /// kg/m³.
    #[serde(default = "default_density")]
    pub density: f64,
    /// Dynamic viscosity, Pa·s.
    #[serde(default = "default_viscosity")]
    pub viscosity: f64,
    /// Linear RGB in [0, 1], for rendering.
    #[serde(default = "default_color")]
    pub color: [f64; 3],
    /// Index of refraction, for rendering.
    #[serde(default = "default_ior")]
    pub ior: f64,
}

impl Default for PhaseSpec {
    /// An unnamed phase with every property at its default.
    fn default() -> Self {
        PhaseSpec {
            name: String::new(),
            density: default_density(),
            viscosity: default_viscosity(),
            color: default_color(),
            ior: default_ior(),
        }
    }
}

fn default_density() -> f64 {
    1000.0
}
fn default_viscosity() -> f64 {
    1.0e-3
}
fn default_color() -> [f64; 3] {
    [0.8, 0.8, 0.8]
}
fn default_ior() -> f64 {
    1.33
}

/// One initial shape as written: `kind` selects which of the optional fields are required.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapeSpec {
    /// Phase name the shape is filled with.
    pub phase: String,
    /// `sphere` (center, radius), `cylinder` (center, radius; axis parallel to z), `ellipsoid`
    /// (center, radii), `box` (lo, hi), `half_space` (point, normal: the phase is on the side the normal points
    /// away from), `wave` (a half-space whose plane is displaced by amplitude·cos(2π(x −
    /// point.x)/wavelength) along the normal) or `mesh` (the inside of a closed triangle mesh
    /// read from the OBJ `file`, then scaled by `scale` and moved by `translate`).
    pub kind: String,
    /// Where this shape overlaps shapes of other phases, the highest priority wins. Overlapping
    /// shapes of different phases with equal priority are an error: nothing says which wins.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub priority: i64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f64>,
    /// `ellipsoid`: the three semi-axes along x, y, z (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radii: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lo: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hi: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub point: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<[f64; 3]>,
    /// `wave` only: displacement amplitude (m) of the plane along its normal.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub amplitude: Option<f64>,
    /// `wave` only: wavelength (m) of the cosine displacement along x.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wavelength: Option<f64>,
    /// `mesh` only: OBJ file, relative to the scene file's folder (or absolute; `builtin:NAME`
    /// names one shipped with the built-in scenes). The resolved scene holds the absolute path.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// `mesh` only: uniform scale applied to the OBJ's coordinates (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// `mesh` only: offset added to the OBJ's coordinates after scaling (default zero).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f64; 3]>,
    /// Half-spaces intersected with the shape (keep the side the normal points away from):
    /// cuts a sphere into halves or wedges.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub clip: Vec<HalfSpaceSpec>,
}

fn is_zero(v: &i64) -> bool {
    *v == 0
}

/// A plane through `point`; the kept side is the one `normal` points away from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HalfSpaceSpec {
    pub point: [f64; 3],
    pub normal: [f64; 3],
}

/// serde's default for switches that are on unless a scene turns them off.
fn default_true() -> bool {
    true
}
