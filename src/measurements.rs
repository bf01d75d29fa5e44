//! What stats report of the interface beyond volumes and timings: the volume correction's
//! share, and the scene's declared measurements (`[[measure]]`): a front is a
//! number, tips are `{min, max}`, a centroid is `[x, y, z]`, pieces are a list of
//! `{volume, centroid, radius, nearest, farthest}`, a velocity profile is
//! `{position: [..], value: [..]}`, contact angles are `{phase: degrees}`; `null` where the
//! phase (or the triple point) is gone.

use std::collections::BTreeMap;

use anyhow::Result;
use polyphase_coupling::{measure, Measured};
use polyphase_scenes::{MeasureKind, Scene};
use polyphase_tracker::LabeledMesh;
use serde_json::{json, Value};

/// Adds each of the scene's measurements of `mesh` to the stats line under its name; the
/// measurements of the fluid (`rise_velocity`, `velocity_profile`, `pressure_jump`, coupled
/// scenes only) come from `fluid`.
pub fn add_measurements(
    line: &mut Value,
    scene: &Scene,
    mesh: &LabeledMesh,
    fluid: &dyn Fn(&MeasureKind) -> Result<Value>,
) -> Result<()> {
    let names = scene.phase_names();
    for m in &scene.measures {
        if let MeasureKind::RiseVelocity { .. }
        | MeasureKind::VelocityProfile { .. }
        | MeasureKind::PressureJump { .. } = m.kind
        {
            line[m.name.as_str()] = fluid(&m.kind)?;
            continue;
        }
        line[m.name.as_str()] = match measure(mesh, &m.kind) {
            Measured::Value(v) => json!(v),
            Measured::Range(r) => {
                r.map_or(Value::Null, |(min, max)| json!({ "min": min, "max": max }))
            }
            Measured::Point(p) => json!(p.map(|p| [p.x, p.y, p.z])),
            Measured::Pieces(pieces) => json!(pieces
                .iter()
                .map(|p| json!({
                    "volume": p.volume,
                    "centroid": [p.centroid.x, p.centroid.y, p.centroid.z],
                    "radius": p.radius,
                    "nearest": p.nearest,
                    "farthest": p.farthest,
                }))
                .collect::<Vec<_>>()),
            Measured::Angles(angles) => match (angles, &m.kind) {
                (Some(angles), MeasureKind::ContactAngles { phases, .. }) => Value::Object(
                    phases
                        .iter()
                        .zip(angles)
                        .map(|(&p, a)| (names[usize::from(p)].clone(), json!(a)))
                        .collect(),
                ),
                _ => Value::Null,
            },
        };
    }
    Ok(())
}

/// Adds `regions` (live regions of a tracker that counts them) and `events` {name: count over
/// the frame} (the front tracker's topology events: merge snaps, T1, T2; the contouring
/// tracker's specks removed), each only when there is one.
pub fn add_topology(line: &mut Value, regions: Option<usize>, events: &[(&'static str, usize)]) {
    if let Some(n) = regions {
        line["regions"] = json!(n);
    }
    if !events.is_empty() {
        let events: BTreeMap<&str, usize> = events.iter().copied().collect();
        line["events"] = json!(events);
    }
}

/// Adds `volume_correction` {phase: volume the correction added over the frame, relative to
/// the phase's initial (exact) volume} for the phases it touched; nothing when it touched none.
pub fn add_volume_correction(line: &mut Value, names: &[String], given: &[f64], volumes: &[f64]) {
    let touched: serde_json::Map<String, Value> = names
        .iter()
        .zip(given.iter().zip(volumes))
        .filter(|(_, (g, v))| **g != 0.0 && **v > 0.0)
        .map(|(n, (g, v))| (n.clone(), json!(g / v)))
        .collect();
    if !touched.is_empty() {
        line["volume_correction"] = Value::Object(touched);
    }
}
