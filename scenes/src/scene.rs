//! A validated scene: the resolved file plus everything derived from it (grid, shapes, flow).

use std::sync::{Arc, OnceLock};

use glam::DVec3;
use polyphase_grid::{GridSpec, PhaseId};

use crate::error::SceneError;
use crate::measure::{compile_measures, Measure};
use crate::tension::{compile_tension, Tension};
use polyphase_tracker::front::flow::{CurlNoise, MeshFlow, PairSpeed};
use polyphase_tracker::front::params::{FrontParams, PASSIVE_CFL};

use crate::format::{
    BoundaryKind, BoundarySpec, HalfSpaceSpec, PairSpeedSpec, PhaseSpec, SceneFile, ShapeSpec,
    SolverSpec, TrackerKind, TrackerSpec, VelocitySpec, WALLS,
};
use crate::mesh_file::SceneBase;
use crate::mesh_sdf::MeshSdf;
use crate::overlap::{find_ambiguous_overlap, DEFAULT_DEPTH as OVERLAP_DEPTH};
use crate::shapes::{InitialPhases, Primitive, Shape};
use crate::velocity::AnalyticVelocity;
use crate::voronoi::Voronoi;

/// Largest accepted tracker resolution: 4096³ nodes is beyond this machine's memory anyway.
const MAX_RESOLUTION: i64 = 4096;

/// A scene that passed validation.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The file with defaults filled in and the domain snapped to whole cells.
    pub file: SceneFile,
    /// The tracker's grid.
    pub grid: GridSpec,
    /// Initial phases.
    pub initial: InitialPhases,
    /// The advecting flow (`Still` for a coupled scene, whose flow is the solver's, and for a
    /// mesh-driven flow).
    pub velocity: AnalyticVelocity,
    /// The mesh-driven flow of a front-tracker scene (`velocity.field = "normal"`, …).
    pub mesh_flow: Option<MeshFlow>,
    /// The solver's grid of a coupled scene (same box as `grid`, cells a whole multiple
    /// larger); `None` for a passive scene.
    pub solver_grid: Option<GridSpec>,
    /// The measurements written to stats every frame, in file order.
    pub measures: Vec<Measure>,
    /// Surface tension per pair of phases (`[[tension]]`).
    pub tension: Tension,
    /// [`Scene::reference_volumes`], computed on first use (the shapes and grid are not changed
    /// after validation): the run loops ask for it at the start and in every frame's stats
    /// line, and recomputing it there cost `dambreak` at 64 about 10 of its 17 s for 6 frames.
    reference: OnceLock<Vec<f64>>,
}

impl Scene {
    /// Parses and validates TOML text; `origin` (a path or `builtin:NAME`) prefixes every error,
    /// and relative OBJ paths of mesh shapes are read from its folder.
    pub fn parse(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let file: SceneFile = toml::from_str(text).map_err(|e| SceneError::Parse {
            origin: origin.to_string(),
            message: one_line(&e.to_string()),
        })?;
        Scene::from_file(file, origin)
    }

    /// Validates a parsed file (`origin` as in [`Scene::parse`]). Mesh shapes' OBJ paths are
    /// written back resolved (absolute, or `builtin:NAME`).
    pub fn from_file(mut file: SceneFile, origin: &str) -> Result<Scene, SceneError> {
        let bad = |place: &str, message: String| SceneError::Invalid {
            origin: origin.to_string(),
            place: place.to_string(),
            message,
        };
        if file.name.trim().is_empty() {
            return Err(bad("name", "must not be empty".into()));
        }
        if !(4..=MAX_RESOLUTION).contains(&file.resolution) {
            return Err(bad(
                "resolution",
                format!(
                    "must be between 4 and {MAX_RESOLUTION} cells, got {}",
                    file.resolution
                ),
            ));
        }
        check_vec(&file.domain.lo, "domain.lo", &bad)?;
        check_vec(&file.domain.hi, "domain.hi", &bad)?;
        for a in 0..3 {
            if file.domain.hi[a] <= file.domain.lo[a] {
                return Err(bad(
                    "domain",
                    format!("hi must exceed lo on every axis (axis {a})"),
                ));
            }
        }
        positive(file.time.end, "time.end", &bad)?;
        positive(file.time.cfl, "time.cfl", &bad)?;
        check_tracker(&mut file.tracker, &bad)?;
        if file.time.frames < 1 {
            return Err(bad(
                "time.frames",
                format!("must be at least 1, got {}", file.time.frames),
            ));
        }
        let velocity = compile_velocity(&file.velocity, &bad)?;
        let ratio = check_solver(&mut file, &bad)?;
        fill_foam_phases(&mut file, &bad)?;
        let phases = compile_phases(&file, &bad)?;
        let find = |name: &str, place: &str| find_phase(&phases, name, place, &bad);
        let background = find(&file.background, "background")?;
        let mesh_flow = compile_mesh_flow(&file.velocity, &find, &bad)?;
        if mesh_flow.is_some() && file.tracker.kind != TrackerKind::Front {
            return Err(bad(
                "velocity.field",
                "moves the interface mesh itself, which only the front tracker has; set \
                 tracker = \"front\""
                    .into(),
            ));
        }
        if let Some(front) = &mut file.tracker.front {
            let passive = ratio.is_none() && mesh_flow.is_none();
            front
                .cfl
                .get_or_insert(if passive { PASSIVE_CFL } else { 1.0 });
            front.exact_start.get_or_insert(!file.tension.is_empty());
        }
        let base = SceneBase::from_origin(origin);
        let mut shapes = file
            .shapes
            .iter_mut()
            .enumerate()
            .map(|(i, s)| {
                let place = format!("shapes[{i}]");
                Ok(Shape {
                    phase: find(&s.phase, &format!("{place}.phase"))?,
                    priority: s.priority,
                    primitive: compile_primitive(s, &place, &base, &bad)?,
                    clip: compile_clip(&s.clip, &place, &bad)?,
                })
            })
            .collect::<Result<Vec<_>, SceneError>>()?;
        let (grid, solver_grid) = snap_grid(&mut file, ratio);
        if let Some((i, j, x)) =
            find_ambiguous_overlap(&shapes, grid.origin, grid.upper(), OVERLAP_DEPTH)
        {
            let (a, b) = (&file.shapes[i], &file.shapes[j]);
            return Err(bad(
                &format!("shapes[{j}]"),
                format!(
                    "overlaps shapes[{i}] near ({:.4}, {:.4}, {:.4}), and their phases ('{}', '{}') \
                     have the same priority {}: give the one that should fill the overlap a higher \
                     `priority`",
                    x.x, x.y, x.z, b.phase, a.phase, a.priority
                ),
            ));
        }
        // Painting order: a later shape wins, so ascending priority (stable: file order among equals).
        shapes.sort_by_key(|s| s.priority);
        let slab_mid = file
            .domain
            .slab
            .then(|| 0.5 * (file.domain.lo[2] + file.domain.hi[2]));
        let measures = compile_measures(
            &file.measure,
            &phases,
            solver_grid.is_some(),
            slab_mid,
            grid.h,
            &bad,
        )?;
        let tension = compile_tension(&file.tension, &phases, solver_grid.is_some(), &bad)?;
        let foam = file.foam.as_ref().map(|f| {
            Arc::new(Voronoi::random(
                f.regions as usize,
                f.seed,
                grid.origin,
                grid.upper(),
            ))
        });
        Ok(Scene {
            file,
            grid,
            initial: InitialPhases {
                background,
                shapes,
                foam,
            },
            velocity,
            mesh_flow,
            solver_grid,
            measures,
            tension,
            reference: OnceLock::new(),
        })
    }

    /// Re-validates with a different resolution and/or frame count (command-line overrides).
    pub fn with_overrides(
        &self,
        resolution: Option<i64>,
        frames: Option<i64>,
    ) -> Result<Scene, SceneError> {
        let mut file = self.file.clone();
        if let Some(r) = resolution {
            // A coupled scene keeps its tracker-to-solver ratio.
            if let Some(spec) = file.solver.as_mut() {
                let ratio = file.resolution / spec.resolution.unwrap_or(file.resolution).max(1);
                spec.resolution = Some(r / ratio.max(1));
            }
            file.resolution = r;
        }
        if let Some(f) = frames {
            file.time.frames = f;
        }
        Scene::from_file(file, "command line")
    }

    /// Re-validates with another tracker (command-line override); the scene's own
    /// `[tracker.front]` parameters are kept when it names the front tracker already.
    pub fn with_tracker(&self, kind: TrackerKind) -> Result<Scene, SceneError> {
        let mut file = self.file.clone();
        if file.tracker.kind != kind {
            file.tracker = TrackerSpec { kind, front: None };
        }
        Scene::from_file(file, "command line")
    }

    /// Exact per-phase volumes of the initial shapes (the reference for volume drift).
    pub fn reference_volumes(&self) -> Vec<f64> {
        self.reference
            .get_or_init(|| self.integrate_reference_volumes())
            .clone()
    }

    /// The adaptive quadrature behind [`Scene::reference_volumes`].
    fn integrate_reference_volumes(&self) -> Vec<f64> {
        if let Some(foam) = &self.initial.foam {
            return foam.cell_volumes();
        }
        let has_mesh = self
            .initial
            .shapes
            .iter()
            .any(|s| matches!(s.primitive, Primitive::Mesh(_)));
        let depth = if has_mesh {
            crate::volume::MESH_DEPTH
        } else {
            crate::volume::DEFAULT_DEPTH
        };
        crate::volume::reference_volumes(&self.initial, &self.grid, self.file.phases.len(), depth)
    }

    /// The volumes the tracker corrects each phase back to: the exact initial ones, or `None`
    /// when the scene turns `volume_correction` off.
    pub fn volume_targets(&self) -> Option<Vec<f64>> {
        self.file
            .volume_correction
            .then(|| self.reference_volumes())
    }

    /// Phase names in id order.
    pub fn phase_names(&self) -> Vec<String> {
        self.file.phases.iter().map(|p| p.name.clone()).collect()
    }

    /// The resolved scene as TOML (every default filled in).
    pub fn to_toml(&self) -> String {
        toml::to_string(&self.file).unwrap_or_default()
    }

    /// True when the solver's velocity moves the interfaces.
    pub fn is_coupled(&self) -> bool {
        self.solver_grid.is_some()
    }

    /// Seconds between frames.
    pub fn frame_dt(&self) -> f64 {
        self.file.time.end / self.file.time.frames as f64
    }

    /// Tracker steps per frame of a passive scene: enough that no step moves a point more
    /// than `travel` (the tracker's [`max_travel`]).
    ///
    /// [`max_travel`]: polyphase_tracker::InterfaceTracker::max_travel
    pub fn steps_per_frame(&self, travel: f64) -> usize {
        let vmax = self.velocity.max_speed(self.grid.origin, self.grid.upper());
        let dt_max = travel / vmax.max(1e-300);
        (self.frame_dt() / dt_max).ceil().max(1.0) as usize
    }
}

/// Fills in the front tracker's defaults and checks them; `[tracker.front]` with the contouring
/// tracker is a mistake worth naming (the parameters would be ignored).
fn check_tracker(spec: &mut TrackerSpec, bad: &Bad) -> Result<(), SceneError> {
    match spec.kind {
        TrackerKind::Contour if spec.front.is_some() => Err(bad(
            "tracker.front",
            "is read only by the front tracker; set tracker.kind = \"front\" or remove it".into(),
        )),
        TrackerKind::Contour => Ok(()),
        TrackerKind::Front => spec
            .front
            .get_or_insert_with(FrontParams::default)
            .validate()
            .map_err(|e| bad("tracker.front", e)),
    }
}

/// Snaps the domain to whole cells of size h = longest extent / resolution (a slab gets
/// exactly two tracker cells in z) and writes the snapped box back into the file. With a
/// solver `ratio` k, the box is snapped to whole solver cells (size k·h) first so both grids
/// cover exactly the same box; a coupled slab is one solver cell thick (two when k = 1).
fn snap_grid(file: &mut SceneFile, ratio: Option<usize>) -> (GridSpec, Option<GridSpec>) {
    let lo = DVec3::from_array(file.domain.lo);
    let ext = DVec3::from_array(file.domain.hi) - lo;
    let longest = if file.domain.slab {
        ext.x.max(ext.y)
    } else {
        ext.max_element()
    };
    let h = longest / file.resolution as f64;
    let k = ratio.unwrap_or(1);
    let hs = h * k as f64;
    let mut coarse = [0usize; 3];
    for (a, d) in coarse.iter_mut().enumerate() {
        *d = ((ext[a] / hs).round() as usize).max(1);
    }
    if file.domain.slab {
        coarse[2] = if k == 1 { 2 } else { 1 };
    }
    let grid = GridSpec {
        origin: lo,
        h,
        dims: coarse.map(|d| d * k),
    };
    file.domain.hi = grid.upper().to_array();
    let solver = ratio.map(|_| GridSpec {
        origin: lo,
        h: hs,
        dims: coarse,
    });
    (grid, solver)
}

/// Checks the `[solver]` table against the velocity and fills its defaults; returns the
/// tracker-to-solver resolution ratio of a coupled scene.
fn check_solver(file: &mut SceneFile, bad: &Bad) -> Result<Option<usize>, SceneError> {
    if file.velocity != VelocitySpec::Fluid {
        if file.solver.is_some() {
            return Err(bad(
                "solver",
                "only a coupled scene (velocity.field = \"fluid\") takes a [solver] table".into(),
            ));
        }
        return Ok(None);
    }
    let spec = file.solver.get_or_insert_with(SolverSpec::default);
    let res = *spec.resolution.get_or_insert((file.resolution / 2).max(1));
    if res < 4 || file.resolution % res != 0 {
        return Err(bad(
            "solver.resolution",
            format!(
                "must be at least 4 and divide the tracker resolution {}, got {res}",
                file.resolution
            ),
        ));
    }
    check_vec(&spec.gravity, "solver.gravity", bad)?;
    positive(spec.cfl, "solver.cfl", bad)?;
    positive(spec.tolerance, "solver.tolerance", bad)?;
    if let Some(m) = spec.max_dt {
        positive(m, "solver.max_dt", bad)?;
    }
    check_boundary(&spec.boundary, bad)?;
    Ok(Some((file.resolution / res) as usize))
}

/// Checks `[solver.boundary]`: each moving wall is a known no-slip wall moving tangentially.
fn check_boundary(spec: &BoundarySpec, bad: &Bad) -> Result<(), SceneError> {
    let axes = spec.axes();
    for (name, v) in &spec.wall_velocity {
        let place = format!("solver.boundary.wall_velocity.{name}");
        let axis = WALLS.iter().position(|w| w == name).ok_or_else(|| {
            bad(
                &place,
                format!("unknown wall (walls: {})", WALLS.join(", ")),
            )
        })? / 2;
        let axis_name = ["x", "y", "z"][axis];
        if axes[axis] != BoundaryKind::NoSlip {
            return Err(bad(
                &place,
                format!(
                    "only a no-slip wall moves, but solver.boundary.{axis_name} is '{}'",
                    axes[axis].name()
                ),
            ));
        }
        check_vec(v, &place, bad)?;
        if v[axis] != 0.0 {
            return Err(bad(
                &format!("{place}[{axis}]"),
                format!(
                    "a wall moves along itself only: the {axis_name} component must be 0, got {}",
                    v[axis]
                ),
            ));
        }
    }
    Ok(())
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

type Bad<'a> = dyn Fn(&str, String) -> SceneError + 'a;

/// The id of the phase called `name`; an unknown name is an error at `place` that lists the
/// scene's phases.
pub(crate) fn find_phase(
    phases: &[String],
    name: &str,
    place: &str,
    bad: &Bad,
) -> Result<PhaseId, SceneError> {
    phases
        .iter()
        .position(|p| p == name)
        .map(|i| i as PhaseId)
        .ok_or_else(|| {
            bad(
                place,
                format!("unknown phase '{name}' (phases: {})", phases.join(", ")),
            )
        })
}

fn finite(v: f64, place: &str, bad: &Bad) -> Result<f64, SceneError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(bad(place, format!("must be a finite number, got {v}")))
    }
}

fn positive(v: f64, place: &str, bad: &Bad) -> Result<f64, SceneError> {
    if finite(v, place, bad)? > 0.0 {
        Ok(v)
    } else {
        Err(bad(place, format!("must be positive, got {v}")))
    }
}

fn check_vec(v: &[f64; 3], place: &str, bad: &Bad) -> Result<DVec3, SceneError> {
    for (i, &c) in v.iter().enumerate() {
        finite(c, &format!("{place}[{i}]"), bad)?;
    }
    Ok(DVec3::from_array(*v))
}

fn unit(v: &[f64; 3], place: &str, bad: &Bad) -> Result<DVec3, SceneError> {
    let n = check_vec(v, place, bad)?;
    if n.length() > 0.0 {
        Ok(n.normalize())
    } else {
        Err(bad(place, "must not be the zero vector".into()))
    }
}

fn compile_velocity(v: &VelocitySpec, bad: &Bad) -> Result<AnalyticVelocity, SceneError> {
    Ok(match v {
        VelocitySpec::Still => AnalyticVelocity::Still,
        VelocitySpec::Rotation {
            center,
            angular_velocity,
        } => AnalyticVelocity::Rotation {
            center: check_vec(center, "velocity.center", bad)?,
            omega: finite(*angular_velocity, "velocity.angular_velocity", bad)?,
        },
        VelocitySpec::Enright { period } => AnalyticVelocity::Enright {
            period: positive(*period, "velocity.period", bad)?,
        },
        VelocitySpec::Vortex { period } => AnalyticVelocity::Vortex {
            period: positive(*period, "velocity.period", bad)?,
        },
        VelocitySpec::Fluid
        | VelocitySpec::Normal { .. }
        | VelocitySpec::NormalFom { .. }
        | VelocitySpec::MeanCurvature { .. }
        | VelocitySpec::CurlNoise { .. } => AnalyticVelocity::Still,
    })
}

/// The mesh-driven flow of `v`, if it is one, with its phases resolved.
fn compile_mesh_flow(
    v: &VelocitySpec,
    find: &dyn Fn(&str, &str) -> Result<PhaseId, SceneError>,
    bad: &Bad,
) -> Result<Option<MeshFlow>, SceneError> {
    let speeds = |list: &[PairSpeedSpec]| -> Result<Vec<PairSpeed>, SceneError> {
        list.iter()
            .enumerate()
            .map(|(i, p)| {
                let place = format!("velocity.speeds[{i}]");
                let from = find(&p.from, &format!("{place}.from"))?;
                let into = find(&p.into, &format!("{place}.into"))?;
                if from == into {
                    return Err(bad(&place, "from and into must be different phases".into()));
                }
                let speed = finite(p.speed, &format!("{place}.speed"), bad)?;
                Ok(PairSpeed { from, into, speed })
            })
            .collect()
    };
    let reversal = |at: Option<f64>| {
        at.map(|at| finite(at, "velocity.reverse_at", bad))
            .transpose()
    };
    Ok(Some(match v {
        VelocitySpec::Normal {
            speeds: s,
            reverse_at,
        } => MeshFlow::Normal {
            speeds: speeds(s)?,
            reverse_at: reversal(*reverse_at)?,
        },
        VelocitySpec::NormalFom {
            speeds: s,
            reverse_at,
        } => MeshFlow::NormalOffset {
            speeds: speeds(s)?,
            reverse_at: reversal(*reverse_at)?,
        },
        VelocitySpec::MeanCurvature { rate } => MeshFlow::MeanCurvature {
            rate: positive(*rate, "velocity.rate", bad)?,
        },
        VelocitySpec::CurlNoise {
            amplitude,
            scale,
            seed,
            speeds: s,
        } => MeshFlow::NoiseAndNormal {
            noise: Box::new(CurlNoise::new(
                positive(*amplitude, "velocity.amplitude", bad)?,
                positive(*scale, "velocity.scale", bad)?,
                *seed,
            )),
            speeds: speeds(s)?,
        },
        _ => return Ok(None),
    }))
}

/// A foam scene's phases: `cell0`…`cellN−1` in colours spread around the hue circle when the
/// file lists none, else exactly one listed phase per cell; a foam has no shapes and is 3D.
fn fill_foam_phases(file: &mut SceneFile, bad: &Bad) -> Result<(), SceneError> {
    let Some(foam) = &file.foam else {
        return Ok(());
    };
    // Phase ids run up to PhaseId::MAX − 1 (compile_phases), the largest is OUTSIDE's.
    let most = PhaseId::MAX as i64 - 1;
    if !(2..=most).contains(&foam.regions) {
        return Err(bad(
            "foam.regions",
            format!("must be between 2 and {most}, got {}", foam.regions),
        ));
    }
    if !file.shapes.is_empty() {
        return Err(bad(
            "shapes",
            "a foam fills the whole domain: remove the shapes or the [foam] table".into(),
        ));
    }
    if file.domain.slab {
        return Err(bad(
            "foam",
            "a foam is three-dimensional: set domain.slab = false".into(),
        ));
    }
    let n = foam.regions as usize;
    if file.phases.is_empty() {
        file.phases = (0..n)
            .map(|k| PhaseSpec {
                name: format!("cell{k}"),
                color: hue_color(k),
                ..PhaseSpec::default()
            })
            .collect();
    } else if file.phases.len() != n {
        return Err(bad(
            "phases",
            format!(
                "a foam of {n} regions needs no phases (cell0…cell{} are made) or exactly {n}, \
                 one per cell; got {}",
                n - 1,
                file.phases.len()
            ),
        ));
    }
    Ok(())
}

/// Linear RGB of hue `k`·0.618… around the circle (golden-ratio steps keep neighbours in
/// index far apart in hue), saturation 0.6, value 0.9.
fn hue_color(k: usize) -> [f64; 3] {
    let h = (k as f64 * 0.618_033_988_749_895).fract() * 6.0;
    let (v, s) = (0.9, 0.6);
    let c = v * s;
    let x = c * (1.0 - (h % 2.0 - 1.0).abs());
    let (r, g, b) = match h as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    [r, g, b].map(|u| u + v - c)
}

fn compile_phases(file: &SceneFile, bad: &Bad) -> Result<Vec<String>, SceneError> {
    if file.phases.is_empty() {
        return Err(bad("phases", "at least one phase is required".into()));
    }
    if file.phases.len() >= PhaseId::MAX as usize {
        return Err(bad(
            "phases",
            format!("at most {} phases", PhaseId::MAX - 1),
        ));
    }
    let mut names: Vec<String> = Vec::with_capacity(file.phases.len());
    for (i, p) in file.phases.iter().enumerate() {
        let place = |f: &str| format!("phases[{i}].{f}");
        if p.name.trim().is_empty() {
            return Err(bad(&place("name"), "must not be empty".into()));
        }
        if names.contains(&p.name) {
            return Err(bad(
                &place("name"),
                format!("phase '{}' is defined twice", p.name),
            ));
        }
        positive(p.density, &place("density"), bad)?;
        if finite(p.viscosity, &place("viscosity"), bad)? < 0.0 {
            return Err(bad(
                &place("viscosity"),
                format!("must not be negative, got {}", p.viscosity),
            ));
        }
        for (c, &v) in p.color.iter().enumerate() {
            if !(0.0..=1.0).contains(&finite(v, &place(&format!("color[{c}]")), bad)?) {
                return Err(bad(
                    &place(&format!("color[{c}]")),
                    format!("must be in [0, 1], got {v}"),
                ));
            }
        }
        if finite(p.ior, &place("ior"), bad)? < 1.0 {
            return Err(bad(
                &place("ior"),
                format!("must be at least 1, got {}", p.ior),
            ));
        }
        names.push(p.name.clone());
    }
    Ok(names)
}

fn compile_primitive(
    s: &mut ShapeSpec,
    place: &str,
    base: &SceneBase,
    bad: &Bad,
) -> Result<Primitive, SceneError> {
    let need3 = |v: Option<[f64; 3]>, field: &str| -> Result<[f64; 3], SceneError> {
        v.ok_or_else(|| {
            bad(
                place,
                format!("kind '{}' needs the field '{field}'", s.kind),
            )
        })
    };
    let radius = || -> Result<f64, SceneError> {
        let r = s
            .radius
            .ok_or_else(|| bad(place, format!("kind '{}' needs the field 'radius'", s.kind)))?;
        positive(r, &format!("{place}.radius"), bad)
    };
    Ok(match s.kind.as_str() {
        "sphere" => Primitive::Sphere {
            center: check_vec(&need3(s.center, "center")?, &format!("{place}.center"), bad)?,
            radius: radius()?,
        },
        "cylinder" => Primitive::Cylinder {
            center: check_vec(&need3(s.center, "center")?, &format!("{place}.center"), bad)?,
            radius: radius()?,
        },
        "box" => {
            let lo = check_vec(&need3(s.lo, "lo")?, &format!("{place}.lo"), bad)?;
            let hi = check_vec(&need3(s.hi, "hi")?, &format!("{place}.hi"), bad)?;
            if hi.cmple(lo).any() {
                return Err(bad(place, "box hi must exceed lo on every axis".into()));
            }
            Primitive::Box { lo, hi }
        }
        "ellipsoid" => {
            let radii = check_vec(&need3(s.radii, "radii")?, &format!("{place}.radii"), bad)?;
            if radii.cmple(DVec3::ZERO).any() {
                return Err(bad(
                    &format!("{place}.radii"),
                    "every radius must be positive".into(),
                ));
            }
            Primitive::Ellipsoid {
                center: check_vec(&need3(s.center, "center")?, &format!("{place}.center"), bad)?,
                radii,
            }
        }
        "half_space" => Primitive::HalfSpace {
            point: check_vec(&need3(s.point, "point")?, &format!("{place}.point"), bad)?,
            normal: unit(&need3(s.normal, "normal")?, &format!("{place}.normal"), bad)?,
        },
        "wave" => {
            let amplitude = s
                .amplitude
                .ok_or_else(|| bad(place, "kind 'wave' needs the field 'amplitude'".into()))?;
            let wavelength = s
                .wavelength
                .ok_or_else(|| bad(place, "kind 'wave' needs the field 'wavelength'".into()))?;
            Primitive::Wave {
                point: check_vec(&need3(s.point, "point")?, &format!("{place}.point"), bad)?,
                normal: unit(&need3(s.normal, "normal")?, &format!("{place}.normal"), bad)?,
                amplitude: finite(amplitude, &format!("{place}.amplitude"), bad)?,
                wavelength: positive(wavelength, &format!("{place}.wavelength"), bad)?,
            }
        }
        "mesh" => compile_mesh(s, place, base, bad)?,
        other => {
            return Err(bad(
                &format!("{place}.kind"),
                format!(
                    "unknown shape kind '{other}' (sphere, cylinder, ellipsoid, box, half_space, wave, mesh)"
                ),
            ))
        }
    })
}

/// Reads, checks and prepares a mesh shape's OBJ; writes its resolved name back into `s`.
fn compile_mesh(
    s: &mut ShapeSpec,
    place: &str,
    base: &SceneBase,
    bad: &Bad,
) -> Result<Primitive, SceneError> {
    let file = s
        .file
        .as_deref()
        .ok_or_else(|| bad(place, "kind 'mesh' needs the field 'file'".into()))?;
    let scale = positive(s.scale.unwrap_or(1.0), &format!("{place}.scale"), bad)?;
    let translate = check_vec(
        &s.translate.unwrap_or([0.0; 3]),
        &format!("{place}.translate"),
        bad,
    )?;
    let at = format!("{place}.file");
    let (resolved, bytes) = crate::mesh_file::read(file, base).map_err(|m| bad(&at, m))?;
    let mesh = crate::obj::parse_obj(&bytes, scale, translate)
        .map_err(|e| bad(&at, format!("{resolved}: {e}")))?;
    s.file = Some(resolved);
    Ok(Primitive::Mesh(Arc::new(MeshSdf::new(&mesh))))
}

fn compile_clip(
    clip: &[HalfSpaceSpec],
    place: &str,
    bad: &Bad,
) -> Result<Vec<(DVec3, DVec3)>, SceneError> {
    clip.iter()
        .enumerate()
        .map(|(i, h)| {
            let p = format!("{place}.clip[{i}]");
            Ok((
                check_vec(&h.point, &format!("{p}.point"), bad)?,
                unit(&h.normal, &format!("{p}.normal"), bad)?,
            ))
        })
        .collect()
}
