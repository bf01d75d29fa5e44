//! Interface measurements declared in the scene file (`[[measure]]`), validated: which
//! quantity, of which phases, written to stats under which name.

use polyphase_grid::PhaseId;

use crate::error::SceneError;
use crate::format::MeasureSpec;
use crate::scene::find_phase;

/// What one measurement reads off the labeled mesh.
#[derive(Clone, Debug, PartialEq)]
pub enum MeasureKind {
    /// The largest coordinate along `axis` of the surface of `phase` (a surge front).
    Front { phase: PhaseId, axis: usize },
    /// The smallest and largest coordinate along `axis` of the interface between two phases
    /// (Rayleigh–Taylor's spike and bubble tips).
    Tips { a: PhaseId, b: PhaseId, axis: usize },
    /// The centre of the volume of `phase`.
    Centroid { phase: PhaseId },
    /// Each connected piece of `phase`: volume, centroid, and its vertices' smallest and
    /// largest distance from the centroid over the equivalent radius (a drop's roundness).
    Pieces { phase: PhaseId },
    /// The mean upward velocity (against gravity) of the solver cells of `phase`: a bubble's
    /// or drop's rise velocity (Hysing et al. 2009). Coupled scenes only.
    RiseVelocity { phase: PhaseId },
    /// The mean of the fluid's velocity `component` over each layer of solver cells across
    /// `axis`, with the layers' centres: a shear flow's profile (two-layer Couette and
    /// Poiseuille validation). Coupled scenes only.
    VelocityProfile { component: usize, axis: usize },
    /// The mean pressure of the solver cells of `inside` minus that of the cells of
    /// `outside`: a static drop's Laplace jump. Coupled scenes only.
    PressureJump { inside: PhaseId, outside: PhaseId },
    /// The circularity of the cross-section of `phase` in the plane z = `z` (a slab's
    /// mid-plane): the perimeter of the circle of the same area over the perimeter of the
    /// phase's interfaces with other phases (Hysing et al. 2009's measure of a 2D bubble's
    /// deformation; 1 for a disc). Slab scenes only.
    Circularity { phase: PhaseId, z: f64 },
    /// The angles (degrees) of the wedges of three `phases` where they meet, averaged along
    /// their triple curves, each interface's direction fitted over `reach` (m) of it: a lens's
    /// contact angles, which Neumann's triangle fixes at rest.
    ContactAngles { phases: [PhaseId; 3], reach: f64 },
}

/// A validated measurement with its stats key.
#[derive(Clone, Debug, PartialEq)]
pub struct Measure {
    pub name: String,
    pub kind: MeasureKind,
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// Validates the scene's `[[measure]]` tables against its phase names (`coupled`: whether the
/// scene has a fluid, which `rise_velocity` needs; `slab_mid`: the z of a slab scene's
/// mid-plane, where `circularity` cuts, `None` for a 3D scene; `h`: the tracker's cell);
/// errors name the table.
pub fn compile_measures(
    specs: &[MeasureSpec],
    phases: &[String],
    coupled: bool,
    slab_mid: Option<f64>,
    h: f64,
    bad: &dyn Fn(&str, String) -> SceneError,
) -> Result<Vec<Measure>, SceneError> {
    let mut out: Vec<Measure> = Vec::with_capacity(specs.len());
    for (i, spec) in specs.iter().enumerate() {
        let place = format!("measure[{i}]");
        let phase_id =
            |name: &str, field: &str| find_phase(phases, name, &format!("{place}.{field}"), bad);
        let one_phase = || -> Result<(PhaseId, &str), SceneError> {
            let name = spec.phase.as_deref().ok_or_else(|| {
                bad(
                    &place,
                    format!("kind '{}' needs the field 'phase'", spec.kind),
                )
            })?;
            Ok((phase_id(name, "phase")?, name))
        };
        let named_axis = |value: Option<&str>, field: &str| -> Result<usize, SceneError> {
            let a = value.ok_or_else(|| {
                bad(
                    &place,
                    format!("kind '{}' needs the field '{field}'", spec.kind),
                )
            })?;
            AXES.iter().position(|x| *x == a).ok_or_else(|| {
                bad(
                    &format!("{place}.{field}"),
                    format!("must be x, y or z, got '{a}'"),
                )
            })
        };
        let axis = || named_axis(spec.axis.as_deref(), "axis");
        let two_phases = || -> Result<(PhaseId, PhaseId, &str, &str), SceneError> {
            let pair = spec.phases.as_deref().unwrap_or_default();
            let [a, b] = pair else {
                return Err(bad(
                    &place,
                    format!(
                        "kind '{}' needs the field 'phases' with two phase names",
                        spec.kind
                    ),
                ));
            };
            let (ia, ib) = (phase_id(a, "phases")?, phase_id(b, "phases")?);
            if ia == ib {
                return Err(bad(
                    &format!("{place}.phases"),
                    format!("needs two different phases, got '{a}' twice"),
                ));
            }
            Ok((ia, ib, a, b))
        };
        let coupled_only = |what: &str| -> Result<(), SceneError> {
            if coupled {
                Ok(())
            } else {
                Err(bad(
                    &format!("{place}.kind"),
                    format!(
                        "'{what}' reads the fluid: it needs a coupled scene \
                         (velocity.field = \"fluid\")"
                    ),
                ))
            }
        };
        let (kind, default_name) = match spec.kind.as_str() {
            "front" => {
                let (phase, name) = one_phase()?;
                let axis = axis()?;
                (
                    MeasureKind::Front { phase, axis },
                    format!("front_{name}_{}", AXES[axis]),
                )
            }
            "tips" => {
                let (ia, ib, a, b) = two_phases()?;
                let axis = axis()?;
                (
                    MeasureKind::Tips { a: ia, b: ib, axis },
                    format!("tips_{a}_{b}_{}", AXES[axis]),
                )
            }
            "centroid" => {
                let (phase, name) = one_phase()?;
                (MeasureKind::Centroid { phase }, format!("centroid_{name}"))
            }
            "pieces" => {
                let (phase, name) = one_phase()?;
                (MeasureKind::Pieces { phase }, format!("pieces_{name}"))
            }
            "rise_velocity" => {
                coupled_only("rise_velocity")?;
                let (phase, name) = one_phase()?;
                (
                    MeasureKind::RiseVelocity { phase },
                    format!("rise_velocity_{name}"),
                )
            }
            "velocity_profile" => {
                coupled_only("velocity_profile")?;
                let component = named_axis(spec.component.as_deref(), "component")?;
                let axis = axis()?;
                (
                    MeasureKind::VelocityProfile { component, axis },
                    format!("velocity_profile_{}_{}", AXES[component], AXES[axis]),
                )
            }
            "pressure_jump" => {
                coupled_only("pressure_jump")?;
                let (inside, outside, a, b) = two_phases()?;
                (
                    MeasureKind::PressureJump { inside, outside },
                    format!("pressure_jump_{a}_{b}"),
                )
            }
            "circularity" => {
                let z = slab_mid.ok_or_else(|| {
                    bad(
                        &format!("{place}.kind"),
                        "'circularity' measures a 2D cross-section: it needs a slab scene \
                         (domain.slab = true)"
                            .into(),
                    )
                })?;
                let (phase, name) = one_phase()?;
                (
                    MeasureKind::Circularity { phase, z },
                    format!("circularity_{name}"),
                )
            }
            "contact_angles" => {
                let names = spec.phases.as_deref().unwrap_or_default();
                let [a, b, c] = names else {
                    return Err(bad(
                        &place,
                        "kind 'contact_angles' needs the field 'phases' with three phase names"
                            .into(),
                    ));
                };
                let ids = [
                    phase_id(a, "phases")?,
                    phase_id(b, "phases")?,
                    phase_id(c, "phases")?,
                ];
                if ids[0] == ids[1] || ids[1] == ids[2] || ids[0] == ids[2] {
                    return Err(bad(
                        &format!("{place}.phases"),
                        "needs three different phases".into(),
                    ));
                }
                (
                    // Over 6 tracker cells, as surface tension's pull on the curve: far enough
                    // from it to miss the contouring's error at the triple point, near enough
                    // for a quadratic to hold the bend.
                    MeasureKind::ContactAngles {
                        phases: ids,
                        reach: 6.0 * h,
                    },
                    format!("contact_angles_{a}_{b}_{c}"),
                )
            }
            other => {
                return Err(bad(
                    &format!("{place}.kind"),
                    format!(
                        "unknown kind '{other}' (kinds: front, tips, centroid, pieces, \
                         rise_velocity, velocity_profile, pressure_jump, circularity, \
                         contact_angles)"
                    ),
                ))
            }
        };
        let name = spec.name.clone().unwrap_or(default_name);
        if name.trim().is_empty() {
            return Err(bad(&format!("{place}.name"), "must not be empty".into()));
        }
        if out.iter().any(|m| m.name == name) {
            return Err(bad(
                &format!("{place}.name"),
                format!("'{name}' is already the name of another measurement"),
            ));
        }
        out.push(Measure { name, kind });
    }
    Ok(out)
}
