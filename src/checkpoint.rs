//! The checkpoint a run writes at every frame end (`DIR/checkpoint.bin`), from which
//! `polyphase resume` continues bit for bit: the tracker's snapshot (for the contouring
//! tracker its mesh, redistanced tree, volume targets and carried volume loss; the body layout
//! is the same as before snapshots existed), the solver's state, time and step count as exact f64
//! bits, plus the run's running totals for the summary. Little-endian binary: magic, format version, body, FNV-1a checksum of all
//! bytes before it, so a truncated or damaged file is refused rather than half-read.

use anyhow::{bail, ensure, Context, Result};
use polyphase_solver::SolverState;
use polyphase_tracker::{ply, MdTree, TrackerSnapshot};

/// File name inside the run folder.
pub const FILE: &str = "checkpoint.bin";

const MAGIC: &[u8; 8] = b"PPHASECK";
const VERSION: u32 = 4;

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
                let mut bytes = Vec::new();
                ply::write_ply(mesh, &mut bytes)?;
                put_u64(&mut w, bytes.len() as u64);
                w.extend_from_slice(&bytes);
                let tree = tree.to_bytes();
                put_u64(&mut w, tree.len() as u64);
                w.extend_from_slice(&tree);
                put_option(&mut w, volume_targets.as_deref(), put_f64s);
                put_f64s(&mut w, component_targets);
                put_f64s(&mut w, carried_loss);
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
        let mesh_len = r.usize()?;
        let mesh = ply::read_ply(r.take(mesh_len)?).context("mesh")?;
        let tree_len = r.usize()?;
        let tree = MdTree::from_bytes(r.take(tree_len)?).context("tree")?;
        let volume_targets = r.option(Reader::f64s)?;
        let component_targets = r.f64s()?;
        let carried_loss = r.f64s()?;
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
            tracker: TrackerSnapshot::Contour {
                mesh,
                tree,
                volume_targets,
                component_targets,
                carried_loss,
            },
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
    use glam::DVec3;
    use polyphase_tracker::{GridSpec, LabeledMesh, PhaseId};

    fn sample() -> Checkpoint {
        let grid = GridSpec {
            origin: DVec3::ZERO,
            h: 0.25,
            dims: [4, 4, 4],
        };
        let ball = |x: DVec3| -> (f64, PhaseId) {
            let d = (x - DVec3::splat(0.5)).length() - 0.3;
            (d.abs(), PhaseId::from(d < 0.0))
        };
        Checkpoint {
            scene_hash: scene_hash(b"name = \"x\""),
            frame: 3,
            time: 0.1 + 0.2,
            steps: 17,
            tracker: TrackerSnapshot::Contour {
                mesh: LabeledMesh {
                    vertices: vec![DVec3::new(0.1, 0.2, 0.3), DVec3::X, DVec3::Y],
                    triangles: vec![[0, 1, 2]],
                    labels: vec![[1, 0]],
                },
                tree: MdTree::build(&grid, &ball),
                volume_targets: Some(vec![1.0 / 3.0, 2.0 / 3.0]),
                component_targets: vec![2.0 / 3.0],
                carried_loss: vec![-1e-7 / 3.0],
            },
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

    #[test]
    fn round_trip_keeps_every_bit() {
        let c = sample();
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
    }

    #[test]
    fn truncated_or_flipped_bytes_are_refused() {
        let bytes = sample().encode().unwrap();
        for cut in [0, 5, 12, bytes.len() / 2, bytes.len() - 1] {
            assert!(Checkpoint::decode(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        for i in [9, 20, bytes.len() / 2, bytes.len() - 3] {
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
