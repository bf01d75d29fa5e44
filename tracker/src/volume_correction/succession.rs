//! How the components of a step's new mesh descend from those of the mesh before it, so that
//! each component's target volume (and the loss it carries) follows it through time.
//!
//! Every interface face of the new mesh is traced back to the departure point of its centroid,
//! and the old face nearest to that point names, for each side, the old component of the same
//! phase there: a vote, weighted by the new face's area, that the new component descends from
//! the old one. A vote links the two when it covers [`LINK_FRACTION`] of either one's interface
//! area (a few faces of a drop that passes close by a neighbour of its phase do not), and each
//! new component is linked to the old one most of its surface comes from. Old and new
//! components joined by links form a group: one of each is a component that continues, several
//! old ones a merge, several new ones a split. Within a group, the old components' sum of a
//! quantity (target, carried loss) is shared among the new ones in proportion to their volumes,
//! and the new ones' volume among the old ones in proportion to their targets. An old component
//! in no group vanished; a new one in no group appeared. A phase with one component before
//! and after the step (a pool, a single ball) is linked without tracing.

use std::collections::BTreeMap;

use glam::DVec3;
use polyphase_grid::OUTSIDE;
use rayon::prelude::*;

use super::components::{root, union, Components, NONE};
use crate::mesh::LabeledMesh;
use crate::query::MeshQuery;

/// The part of either component's interface area a vote must cover to link them.
pub const LINK_FRACTION: f64 = 0.1;

/// The groups of old and new components that descend from one another.
#[derive(Clone, Debug, PartialEq)]
pub struct Succession {
    /// Per old component, its group; [`NONE`] when it vanished.
    old_group: Vec<u32>,
    /// Per new component, its group; [`NONE`] when it appeared.
    new_group: Vec<u32>,
    groups: usize,
}

impl Succession {
    /// The groups that the links `(old, new)` join (indices into the old and new components).
    pub fn from_links(n_old: usize, n_new: usize, links: &[(u32, u32)]) -> Succession {
        let mut parent: Vec<u32> = (0..(n_old + n_new) as u32).collect();
        let mut linked = vec![false; n_old + n_new];
        for &(i, j) in links {
            union(&mut parent, i, n_old as u32 + j);
            linked[i as usize] = true;
            linked[n_old + j as usize] = true;
        }
        let mut number = vec![NONE; n_old + n_new];
        let mut groups = 0;
        let mut group: Vec<u32> = (0..n_old + n_new)
            .map(|node| {
                if !linked[node] {
                    return NONE;
                }
                let r = root(&mut parent, node as u32) as usize;
                if number[r] == NONE {
                    number[r] = groups as u32;
                    groups += 1;
                }
                number[r]
            })
            .collect();
        let new_group = group.split_off(n_old);
        Succession {
            old_group: group,
            new_group,
            groups,
        }
    }

    /// Traces the components `new` of `mesh` back to the components `old` of `previous` (whose
    /// query is `query`), `departure` giving the departure point of a point of `mesh`.
    pub fn trace(
        previous: &LabeledMesh,
        query: &MeshQuery,
        old: &Components,
        mesh: &LabeledMesh,
        new: &Components,
        departure: &(dyn Fn(DVec3) -> DVec3 + Sync),
    ) -> Succession {
        // A phase with at most one component before and after needs no tracing.
        let phases = old
            .phase
            .iter()
            .chain(&new.phase)
            .max()
            .map_or(0, |&p| p as usize + 1);
        let (before, after) = (old.count_per_phase(phases), new.count_per_phase(phases));
        let traced: Vec<bool> = (0..phases).map(|p| before[p] > 1 || after[p] > 1).collect();
        let mut links: Vec<(u32, u32)> = (0..new.len())
            .filter(|&j| !traced[new.phase[j] as usize])
            .filter_map(|j| {
                let i = old.phase.iter().position(|&p| p == new.phase[j])?;
                Some((i as u32, j as u32))
            })
            .collect();
        let votes: Vec<[Option<(u32, u32)>; 2]> = (0..mesh.triangle_count())
            .into_par_iter()
            .map(|f| {
                let sides = new.sides[f];
                let wanted = |s: usize| sides[s] != NONE && traced[mesh.labels[f][s] as usize];
                if mesh.labels[f].contains(&OUTSIDE) || !(wanted(0) || wanted(1)) {
                    return [None; 2];
                }
                let [a, b, c] = mesh.corners(f);
                let Some(t0) = query.nearest_triangle(departure((a + b + c) / 3.0)) else {
                    return [None; 2];
                };
                [0, 1].map(|s| {
                    if !wanted(s) {
                        return None;
                    }
                    let j = sides[s];
                    let phase = mesh.labels[f][s];
                    let s0 = previous.labels[t0].iter().position(|&p| p == phase)?;
                    let i = old.sides[t0][s0];
                    (i != NONE && j != NONE).then_some((i, j))
                })
            })
            .collect();
        let mut weight: BTreeMap<(u32, u32), f64> = BTreeMap::new();
        for (f, pair) in votes.iter().enumerate() {
            for &link in pair.iter().flatten() {
                *weight.entry(link).or_default() += mesh.area(f);
            }
        }
        let mut strongest: Vec<Option<(f64, u32)>> = vec![None; new.len()];
        for (&(i, j), &w) in &weight {
            let best = &mut strongest[j as usize];
            if best.is_none_or(|(b, _)| w > b) {
                *best = Some((w, i));
            }
        }
        links.extend(
            weight
                .iter()
                .filter(|(&(i, j), &w)| {
                    let least = old.area[i as usize].min(new.area[j as usize]);
                    w >= LINK_FRACTION * least || strongest[j as usize].map(|(_, s)| s) == Some(i)
                })
                .map(|(&link, _)| link),
        );
        Succession::from_links(old.len(), new.len(), &links)
    }

    /// Per old component, the volume its group ended the step with, shared among the group's
    /// old components in proportion to `weights` (their targets; equally when those are all
    /// zero); zero for one that vanished.
    pub fn pull_back(&self, new_volumes: &[f64], weights: &[f64]) -> Vec<f64> {
        let volume = self.sum(&self.new_group, new_volumes);
        let total = self.sum(&self.old_group, weights);
        let count = self.sum(&self.old_group, &vec![1.0; weights.len()]);
        self.old_group
            .iter()
            .zip(weights)
            .map(|(&g, &w)| match g {
                NONE => 0.0,
                g if total[g as usize] > 0.0 => volume[g as usize] * w / total[g as usize],
                g => volume[g as usize] / count[g as usize],
            })
            .collect()
    }

    /// Per new component, its share of its group's sum of `old_values`, in proportion to the
    /// group's new volumes (equally when those are all zero); `None` for one that appeared.
    pub fn push_forward(&self, old_values: &[f64], new_volumes: &[f64]) -> Vec<Option<f64>> {
        let positive: Vec<f64> = new_volumes.iter().map(|v| v.max(0.0)).collect();
        let sum = self.sum(&self.old_group, old_values);
        let volume = self.sum(&self.new_group, &positive);
        let count = self.sum(&self.new_group, &vec![1.0; positive.len()]);
        self.new_group
            .iter()
            .zip(&positive)
            .map(|(&g, &v)| {
                let g = (g != NONE).then_some(g as usize)?;
                Some(if volume[g] > 0.0 {
                    sum[g] * v / volume[g]
                } else {
                    sum[g] / count[g]
                })
            })
            .collect()
    }

    /// Per group, the sum of `values` over the members `group` lists.
    fn sum(&self, group: &[u32], values: &[f64]) -> Vec<f64> {
        let mut sums = vec![0.0; self.groups];
        for (&g, &v) in group.iter().zip(values) {
            if g != NONE {
                sums[g as usize] += v;
            }
        }
        sums
    }
}

/// The targets of a mesh's components: each inherits its share ([`Succession::push_forward`];
/// one that appeared gets its own volume), then the difference between each phase's target and
/// its components' sum (what vanished, less what appeared) is shared among the phase's
/// components in proportion to their volumes, so the phase keeps its target. With nothing
/// inherited this shares each phase's target by volume: the targets of a first mesh.
pub fn share_targets(
    inherited: &[Option<f64>],
    components: &Components,
    phase_targets: &[f64],
) -> Vec<f64> {
    let mut targets: Vec<f64> = inherited
        .iter()
        .zip(&components.volume)
        .map(|(t, &v)| t.unwrap_or(v))
        .collect();
    for (phase, &target) in phase_targets.iter().enumerate() {
        let of_phase = || (0..components.len()).filter(|&c| components.phase[c] as usize == phase);
        let volume: f64 = of_phase().map(|c| components.volume[c]).sum();
        if volume <= 0.0 {
            continue;
        }
        let residual = target - of_phase().map(|c| targets[c]).sum::<f64>();
        for c in of_phase() {
            targets[c] += residual * components.volume[c] / volume;
        }
    }
    targets
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Old components A, B, C, E, D of one phase become A′ (A continues), BC′ (B and C merge),
    /// E1 and E2 (E splits) and a speck S that appeared; D vanished.
    #[test]
    fn targets_follow_continue_merge_and_split() {
        let old_targets = [1.0, 2.0, 0.5, 3.0, 0.1];
        let links = [(0, 0), (1, 1), (2, 1), (3, 2), (3, 3)];
        let succession = Succession::from_links(5, 5, &links);
        let new = Components {
            phase: vec![1; 5],
            volume: vec![0.95, 2.4, 1.0, 2.0, 0.02],
            area: vec![1.0; 5],
            sides: Vec::new(),
        };
        let inherited = succession.push_forward(&old_targets, &new.volume);
        assert_eq!(inherited[0], Some(1.0), "continues: keeps its target");
        assert_eq!(inherited[1], Some(2.5), "merge: the targets add");
        // Split 1 : 2 by volume; the shares are exact in binary up to one rounding.
        assert!((inherited[2].unwrap() - 1.0).abs() < 1e-15);
        assert!((inherited[3].unwrap() - 2.0).abs() < 1e-15);
        assert_eq!(inherited[4], None, "appeared");

        let phase_target: f64 = old_targets.iter().sum();
        let targets = share_targets(&inherited, &new, &[0.0, phase_target]);
        // What vanished (D's 0.1) less what appeared (S's own 0.02) is shared by volume.
        let residual = 0.1 - 0.02;
        let volume: f64 = new.volume.iter().sum();
        let expected = [1.0, 2.5, 1.0, 2.0, 0.02];
        for c in 0..5 {
            let want = expected[c] + residual * new.volume[c] / volume;
            // A handful of additions of numbers of order 1: rounding only.
            assert!((targets[c] - want).abs() < 1e-14, "{c}: {}", targets[c]);
        }
        assert!((targets.iter().sum::<f64>() - phase_target).abs() < 1e-14);

        let after = succession.pull_back(&new.volume, &old_targets);
        // A keeps its own volume; B and C share BC′ 4 : 1 by target; E gets E1 + E2; D none.
        let want = [0.95, 1.92, 0.48, 3.0, 0.0];
        for i in 0..5 {
            assert!((after[i] - want[i]).abs() < 1e-15, "{i}: {}", after[i]);
        }
    }

    /// With nothing inherited, a phase's target is shared among its components by volume, and
    /// a phase without components is left as it is.
    #[test]
    fn first_targets_share_the_phase_target_by_volume() {
        let components = Components {
            phase: vec![1, 2, 1],
            volume: vec![1.0, 4.0, 3.0],
            area: vec![1.0; 3],
            sides: Vec::new(),
        };
        let targets = share_targets(&[None; 3], &components, &[9.0, 8.8, 4.0, 1.0]);
        // Phase 1 (volume 4) gets 8.8 as 2.2 + 6.6; phase 2 its own 4; rounding only.
        for (t, want) in targets.iter().zip([2.2, 4.0, 6.6]) {
            assert!((t - want).abs() < 1e-14, "{targets:?}");
        }
    }
}
