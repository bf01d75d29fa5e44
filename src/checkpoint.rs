//! The checkpoint a run writes at every frame end (`DIR/checkpoint.bin`), from which
//! `polyphase resume` continues bit for bit: the tracker's snapshot behind a tag byte of its
//! kind (the contouring tracker's mesh, tree, volume targets and carried volume
//! loss; the front tracker's [`FrontState`]), the solver's state, time and step count as exact
//! f64 bits, plus the run's running totals for the summary. Little-endian binary: magic, format
//! version, body, FNV-1a checksum of all bytes before it, so a truncated or damaged file is
//! refused rather than half-read.

use anyhow::{bail, ensure, Context, Result};
use glam::DVec3;
use polyphase_solver::SolverState;
use polyphase_tracker::front::front_tracker::{FrontState, FrontStepReport, TopologyCounts};
use polyphase_tracker::front::remesh::RemeshStats;
use polyphase_tracker::{ply, LabeledMesh, MdTree, TrackerSnapshot};

/// File name inside the run folder.
pub const FILE: &str = "checkpoint.bin";

const MAGIC: &[u8; 8] = b"PPHASECK";
const VERSION: u32 = 7;

/// Tracker kind tags, the first byte of the tracker's part of the body.
const CONTOUR: u8 = 0;
const FRONT: u8 = 1;

/// Counts in a [`FrontStepReport`].
const REPORT_COUNTS: usize = 16;

/// Running totals of a run (timings differ between runs; they only feed the summary).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Totals {
    /// Wall seconds of the frame loop so far.
    pub wall: f64,
    /// Pressure CG iterations so far (coupled runs).
    pub pressure_iterations: usize,
    /// Viscosity CG iterations so far (coupled runs).
    pub viscosity_iterations: usize,
    /// Seconds per stage so far, in the order the stages first ran.
    pub stages: Vec<(String, f64)>,
}

/// The state at the end of frame `frame`.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    /// [`scene_hash`] of the `scene.toml` the run was started with.
    pub scene_hash: u64,
    /// Last frame written.
    pub frame: usize,
    /// Simulated time (s).
    pub time: f64,
    /// Steps taken (coupled steps, or tracker steps of a passive run).
    pub steps: usize,
    /// The tracker's state ([`InterfaceTracker::snapshot`]).
    pub tracker: TrackerSnapshot,
    /// The solver's state; `None` for a passive run.
    pub solver: Option<SolverState>,
    /// Totals for the summary.
    pub totals: Totals,
}

/// FNV-1a (64-bit) of `bytes`: the checksum, and the fingerprint of `scene.toml` that stops a
/// resume against an edited scene.
pub fn scene_hash(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

impl Checkpoint {
    /// The file's bytes.
    pub fn encode(&self) -> Result<Vec<u8>> {
        let mut w = Vec::new();
        w.extend_from_slice(MAGIC);
        w.extend_from_slice(&VERSION.to_le_bytes());
        put_u64(&mut w, self.scene_hash);
        put_u64(&mut w, self.frame as u64);
        put_f64(&mut w, self.time);
        put_u64(&mut w, self.steps as u64);
        match &self.tracker {
            TrackerSnapshot::Contour {
                mesh,
                tree,
                volume_targets,
                component_targets,
                carried_loss,
            } => {
                w.push(CONTOUR);
                put_mesh(&mut w, mesh)?;
                let tree = tree.to_bytes();
                put_u64(&mut w, tree.len() as u64);
                w.extend_from_slice(&tree);
                put_option(&mut w, volume_targets.as_deref(), put_f64s);
                put_f64s(&mut w, component_targets);
                put_f64s(&mut w, carried_loss);
            }
            TrackerSnapshot::Front(state) => {
                w.push(FRONT);
                put_mesh(&mut w, &state.mesh)?;
                put_f64(&mut w, state.target);
                put_option(&mut w, state.domain.as_ref(), |w, (lo, hi)| {
                    put_f64s(w, &[lo.x, lo.y, lo.z, hi.x, hi.y, hi.z])
                });
                put_f64(&mut w, state.detached_volume);
                put_u64(&mut w, state.flow_steps);
                report_counts(&state.report)
                    .iter()
                    .for_each(|&n| put_u64(&mut w, n as u64));
            }
        }
        put_option(&mut w, self.solver.as_ref(), |w, s| {
            put_f64(w, s.time);
            s.velocity.iter().for_each(|c| put_f64s(w, c));
            put_f64s(w, &s.pressure);
            put_option(w, s.owners.as_ref(), |w, o| {
                o.iter().for_each(|c| put_u16s(w, c))
            });
            put_option(w, s.seed_phases.as_ref(), |w, o| {
                o.iter().for_each(|c| put_u16s(w, c))
            });
        });
        let t = &self.totals;
        put_f64(&mut w, t.wall);
        put_u64(&mut w, t.pressure_iterations as u64);
        put_u64(&mut w, t.viscosity_iterations as u64);
        put_u64(&mut w, t.stages.len() as u64);
        for (name, secs) in &t.stages {
            put_u64(&mut w, name.len() as u64);
            w.extend_from_slice(name.as_bytes());
            put_f64(&mut w, *secs);
        }
        let sum = scene_hash(&w);
        put_u64(&mut w, sum);
        Ok(w)
    }

    /// Reads a checkpoint, refusing a damaged, truncated or other-version file.
    pub fn decode(bytes: &[u8]) -> Result<Checkpoint> {
        ensure!(
            bytes.len() >= MAGIC.len() + 4 + 8 && bytes.starts_with(MAGIC),
            "not a polyphase checkpoint"
        );
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        ensure!(
            scene_hash(body).to_le_bytes() == sum,
            "checksum mismatch (truncated or damaged)"
        );
        let mut r = Reader {
            rest: &body[MAGIC.len()..],
        };
        let version = u32::from_le_bytes(r.array()?);
        ensure!(
            version == VERSION,
            "format version {version}, this program reads version {VERSION}"
        );
        let scene_hash = r.u64()?;
        let frame = r.usize()?;
        let time = r.f64()?;
        let steps = r.usize()?;
        let tracker = match r.take(1)?[0] {
            CONTOUR => {
                let mesh = r.mesh()?;
                let tree_len = r.usize()?;
                let tree = MdTree::from_bytes(r.take(tree_len)?).context("tree")?;
                TrackerSnapshot::Contour {
                    mesh,
                    tree,
                    volume_targets: r.option(Reader::f64s)?,
                    component_targets: r.f64s()?,
                    carried_loss: r.f64s()?,
                }
            }
            FRONT => TrackerSnapshot::Front(FrontState {
                mesh: r.mesh()?,
                target: r.f64()?,
                domain: r.option(|r| match r.f64s()?[..] {
                    [a, b, c, d, e, f] => Ok((DVec3::new(a, b, c), DVec3::new(d, e, f))),
                    ref v => bail!("domain box of {} numbers", v.len()),
                })?,
                detached_volume: r.f64()?,
                flow_steps: r.u64()?,
                report: {
                    let mut counts = [0; REPORT_COUNTS];
                    for n in &mut counts {
                        *n = r.usize()?;
                    }
                    report_from_counts(counts)
                },
            }),
            b => bail!("unknown tracker kind {b}"),
        };
        let solver = r.option(|r| {
            Ok(SolverState {
                time: r.f64()?,
                velocity: [r.f64s()?, r.f64s()?, r.f64s()?],
                pressure: r.f64s()?,
                owners: r.option(|r| Ok([r.u16s()?, r.u16s()?, r.u16s()?]))?,
                seed_phases: r.option(|r| Ok([r.u16s()?, r.u16s()?, r.u16s()?]))?,
            })
        })?;
        let wall = r.f64()?;
        let pressure_iterations = r.usize()?;
        let viscosity_iterations = r.usize()?;
        let n = r.usize()?;
        let mut stages = Vec::new();
        for _ in 0..n {
            let len = r.usize()?;
            let name = String::from_utf8(r.take(len)?.to_vec()).context("stage name")?;
            stages.push((name, r.f64()?));
        }
        ensure!(r.rest.is_empty(), "{} bytes left over", r.rest.len());
        Ok(Checkpoint {
            scene_hash,
            frame,
            time,
            steps,
            tracker,
            solver,
            totals: Totals {
                wall,
                pressure_iterations,
                viscosity_iterations,
                stages,
            },
        })
    }
}

/// A mesh as its length-prefixed PLY bytes (coordinates as exact f64 bits).
fn put_mesh(w: &mut Vec<u8>, mesh: &LabeledMesh) -> Result<()> {
    let mut bytes = Vec::new();
    ply::write_ply(mesh, &mut bytes)?;
    put_u64(w, bytes.len() as u64);
    w.extend_from_slice(&bytes);
    Ok(())
}

/// The counts of a front step report in a fixed order, the inverse of [`report_from_counts`].
fn report_counts(r: &FrontStepReport) -> [usize; REPORT_COUNTS] {
    let (m, t) = (&r.remesh, &r.topology);
    [
        m.splits,
        m.collapses,
        m.flips,
        m.smoothed,
        m.unsafe_cancelled,
        m.bound_cancelled,
        m.failsafe,
        r.substeps,
        r.dropped,
        r.flow_substeps,
        t.snaps,
        t.junction_collapses,
        t.separations,
        t.degenerate,
        t.vanished,
        t.needles,
    ]
}

/// The front step report of [`report_counts`]'s order.
fn report_from_counts(n: [usize; REPORT_COUNTS]) -> FrontStepReport {
    FrontStepReport {
        remesh: RemeshStats {
            splits: n[0],
            collapses: n[1],
            flips: n[2],
            smoothed: n[3],
            unsafe_cancelled: n[4],
            bound_cancelled: n[5],
            failsafe: n[6],
        },
        substeps: n[7],
        dropped: n[8],
        flow_substeps: n[9],
        topology: TopologyCounts {
            snaps: n[10],
            junction_collapses: n[11],
            separations: n[12],
            degenerate: n[13],
            vanished: n[14],
            needles: n[15],
        },
    }
}

fn put_u64(w: &mut Vec<u8>, v: u64) {
    w.extend_from_slice(&v.to_le_bytes());
}

fn put_f64(w: &mut Vec<u8>, v: f64) {
    w.extend_from_slice(&v.to_bits().to_le_bytes());
}

fn put_f64s(w: &mut Vec<u8>, v: &[f64]) {
    put_u64(w, v.len() as u64);
    v.iter().for_each(|&x| put_f64(w, x));
}

fn put_u16s(w: &mut Vec<u8>, v: &[u16]) {
    put_u64(w, v.len() as u64);
    v.iter()
        .for_each(|&x| w.extend_from_slice(&x.to_le_bytes()));
}

fn put_option<T: ?Sized>(w: &mut Vec<u8>, v: Option<&T>, put: impl Fn(&mut Vec<u8>, &T)) {
    match v {
        Some(v) => {
            w.push(1);
            put(w, v);
        }
        None => w.push(0),
    }
}

/// Bounds-checked little-endian reads over the checkpoint body.
struct Reader<'a> {
    rest: &'a [u8],
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8]> {
        ensure!(n <= self.rest.len(), "truncated");
        let (head, tail) = self.rest.split_at(n);
        self.rest = tail;
        Ok(head)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N]> {
        let mut a = [0; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }

    fn u64(&mut self) -> Result<u64> {
        Ok(u64::from_le_bytes(self.array()?))
    }

    fn usize(&mut self) -> Result<usize> {
        usize::try_from(self.u64()?).context("count out of range")
    }

    fn f64(&mut self) -> Result<f64> {
        Ok(f64::from_bits(self.u64()?))
    }

    fn mesh(&mut self) -> Result<LabeledMesh> {
        let len = self.usize()?;
        ply::read_ply(self.take(len)?).context("mesh")
    }

    fn f64s(&mut self) -> Result<Vec<f64>> {
        let n = self.usize()?;
        // Checked before allocating, so a damaged count cannot ask for huge memory.
        ensure!(n <= self.rest.len() / 8, "truncated");
        (0..n).map(|_| self.f64()).collect()
    }

    fn u16s(&mut self) -> Result<Vec<u16>> {
        let n = self.usize()?;
        ensure!(n <= self.rest.len() / 2, "truncated");
        (0..n)
            .map(|_| Ok(u16::from_le_bytes(self.array()?)))
            .collect()
    }

    fn option<T>(&mut self, read: impl FnOnce(&mut Self) -> Result<T>) -> Result<Option<T>> {
        match self.take(1)?[0] {
            0 => Ok(None),
            1 => read(self).map(Some),
            b => bail!("bad option tag {b}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use polyphase_tracker::{GridSpec, PhaseId};

    /// A checkpoint around `tracker` with every other field set to awkward values.
    fn sample(tracker: TrackerSnapshot) -> Checkpoint {
        Checkpoint {
            scene_hash: scene_hash(b"name = \"x\""),
            frame: 3,
            time: 0.1 + 0.2,
            steps: 17,
            tracker,
            solver: Some(SolverState {
                time: 0.3000000000000001,
                velocity: [vec![1e-300, -0.0], vec![f64::MIN_POSITIVE], vec![]],
                pressure: vec![101325.0, 7.0 / 9.0],
                owners: Some([vec![0, 1], vec![2], vec![]]),
                seed_phases: Some([vec![1, 65535, 0, 2], vec![65535, 65535], vec![]]),
            }),
            totals: Totals {
                wall: 1.5,
                pressure_iterations: 40,
                viscosity_iterations: 2,
                stages: vec![("build".into(), 0.25), ("write".into(), 0.125)],
            },
        }
    }

    /// One triangle.
    fn mesh() -> LabeledMesh {
        LabeledMesh {
            vertices: vec![DVec3::new(0.1, 0.2, 0.3), DVec3::X, DVec3::Y],
            triangles: vec![[0, 1, 2]],
            labels: vec![[1, 0]],
        }
    }

    /// A checkpoint of each tracker kind.
    fn samples() -> [Checkpoint; 2] {
        let grid = GridSpec {
            origin: DVec3::ZERO,
            h: 0.25,
            dims: [4, 4, 4],
        };
        let ball = |x: DVec3| -> (f64, PhaseId) {
            let d = (x - DVec3::splat(0.5)).length() - 0.3;
            (d.abs(), PhaseId::from(d < 0.0))
        };
        let contour = TrackerSnapshot::Contour {
            mesh: mesh(),
            tree: MdTree::build(&grid, &ball),
            volume_targets: Some(vec![1.0 / 3.0, 2.0 / 3.0]),
            component_targets: vec![2.0 / 3.0],
            carried_loss: vec![-1e-7 / 3.0],
        };
        let mut report = FrontStepReport {
            substeps: 3,
            flow_substeps: 2,
            ..FrontStepReport::default()
        };
        report.remesh.failsafe = 1;
        report.topology.vanished = 4;
        let front = TrackerSnapshot::Front(FrontState {
            mesh: mesh(),
            target: 1.0 / 48.0,
            domain: Some((DVec3::splat(-0.0), DVec3::new(1.0, 2.0, 1.0 / 3.0))),
            detached_volume: 0.1 + 0.7,
            flow_steps: 41,
            report,
        });
        [sample(contour), sample(front)]
    }

    #[test]
    fn round_trip_keeps_every_bit() {
        for c in samples() {
            let bytes = c.encode().unwrap();
            let back = Checkpoint::decode(&bytes).unwrap();
            // Every field is written as its exact bits, so equal bytes mean an exact copy.
            assert_eq!(back.encode().unwrap(), bytes);
            assert_eq!(back.tracker.mesh(), c.tracker.mesh());
            assert_eq!(back.solver, c.solver);
            assert_eq!(back.totals, c.totals);
            // PartialEq on f64 would accept 0.0 for -0.0: compare the bits of the signed zero too.
            let v = &back.solver.as_ref().unwrap().velocity[0];
            assert_eq!(v[1].to_bits(), (-0.0f64).to_bits());
            if let (TrackerSnapshot::Front(a), TrackerSnapshot::Front(b)) =
                (&back.tracker, &c.tracker)
            {
                assert_eq!(a, b);
                let (lo, _) = a.domain.unwrap();
                assert_eq!(lo.x.to_bits(), (-0.0f64).to_bits());
            }
        }
    }

    #[test]
    fn truncated_or_flipped_bytes_are_refused() {
        for c in samples() {
            let bytes = c.encode().unwrap();
            for cut in [0, 5, 12, bytes.len() / 2, bytes.len() - 1] {
                assert!(Checkpoint::decode(&bytes[..cut]).is_err(), "cut at {cut}");
            }
            // The header, the tracker's tag and body, the middle, the checksum.
            for i in [9, 20, 36, 60, bytes.len() / 2, bytes.len() - 3] {
                let mut bad = bytes.clone();
                bad[i] ^= 0x10;
                let err = Checkpoint::decode(&bad).unwrap_err().to_string();
                assert!(
                    err.contains("checksum") || err.contains("not a polyphase"),
                    "{err}"
                );
            }
        }
    }

    #[test]
    fn an_unknown_tracker_kind_is_refused() {
        let mut bytes = samples()[1].encode().unwrap();
        // The tag follows magic, version, scene hash, frame, time and steps.
        let tag = MAGIC.len() + 4 + 4 * 8;
        assert_eq!(bytes[tag], FRONT);
        bytes[tag] = 7;
        let body = bytes.len() - 8;
        let sum = scene_hash(&bytes[..body]);
        bytes[body..].copy_from_slice(&sum.to_le_bytes());
        let err = Checkpoint::decode(&bytes).unwrap_err().to_string();
        assert!(err.contains("unknown tracker kind 7"), "{err}");
    }
}
