//! Surface tension declared in the scene file (`[[tension]]`), validated: one σ per pair of
//! phases, the Surface Evolver convention paper 000 cites in §3 (each interface carries the
//! tension of the two phases it separates).

use polyphase_grid::PhaseId;

use crate::error::SceneError;
use crate::format::TensionSpec;
use crate::scene::find_phase;

/// The tension coefficients of a scene: σ for every ordered pair, 0 where none was given.
#[derive(Clone, Debug, PartialEq)]
pub struct Tension {
    n: usize,
    sigma: Vec<f64>,
}

impl Tension {
    /// σ (N/m) of the interface between phases `a` and `b` (0 for `a == b` or an unlisted pair).
    pub fn sigma(&self, a: PhaseId, b: PhaseId) -> f64 {
        let (a, b) = (usize::from(a), usize::from(b));
        if a < self.n && b < self.n {
            self.sigma[a * self.n + b]
        } else {
            0.0
        }
    }

    /// Whether any pair has a tension.
    pub fn any(&self) -> bool {
        self.sigma.iter().any(|&s| s > 0.0)
    }

    /// The pairs with a tension, (a, b, σ) with a < b.
    pub fn pairs(&self) -> Vec<(PhaseId, PhaseId, f64)> {
        let mut out = Vec::new();
        for a in 0..self.n {
            for b in a + 1..self.n {
                let s = self.sigma[a * self.n + b];
                if s > 0.0 {
                    out.push((a as PhaseId, b as PhaseId, s));
                }
            }
        }
        out
    }

    /// Triples of phases (ascending) whose tensions have no Neumann triangle: one σ is at least
    /// the sum of the other two (an unlisted pair counts 0), with at least two of them
    /// non-zero. Where such three meet no angles balance the pulls on their triple curve (the
    /// phase between the other two spreads), so its pull never vanishes; `balls` with tension
    /// only against air saw its step fall fivefold there (README, "Surface tension").
    pub fn unbalanced_triples(&self) -> Vec<[PhaseId; 3]> {
        let mut out = Vec::new();
        for a in 0..self.n {
            for b in a + 1..self.n {
                for c in b + 1..self.n {
                    let mut s = [
                        self.sigma[a * self.n + b],
                        self.sigma[a * self.n + c],
                        self.sigma[b * self.n + c],
                    ];
                    s.sort_by(f64::total_cmp);
                    if s[1] > 0.0 && s[2] >= s[0] + s[1] {
                        out.push([a, b, c].map(|p| p as PhaseId));
                    }
                }
            }
        }
        out
    }
}

/// Checks the `[[tension]]` entries against the phase names: known and distinct phases, σ
/// finite and ≥ 0, each pair at most once; a passive scene (no fluid to pull) may have none.
pub(crate) fn compile_tension(
    specs: &[TensionSpec],
    phases: &[String],
    coupled: bool,
    bad: &dyn Fn(&str, String) -> SceneError,
) -> Result<Tension, SceneError> {
    let n = phases.len();
    let mut sigma = vec![0.0; n * n];
    let mut given = vec![false; n * n];
    for (i, spec) in specs.iter().enumerate() {
        let place = format!("tension[{i}]");
        if !coupled {
            return Err(bad(
                &place,
                "surface tension acts through the fluid solver: add a [solver] table and \
                 velocity.field = \"fluid\", or remove it"
                    .into(),
            ));
        }
        let a = find_phase(phases, &spec.phases[0], &format!("{place}.phases[0]"), bad)?;
        let b = find_phase(phases, &spec.phases[1], &format!("{place}.phases[1]"), bad)?;
        if a == b {
            return Err(bad(
                &format!("{place}.phases"),
                format!(
                    "names '{}' twice: a tension acts between two phases",
                    spec.phases[0]
                ),
            ));
        }
        if !(spec.sigma.is_finite() && spec.sigma >= 0.0) {
            return Err(bad(
                &format!("{place}.sigma"),
                format!("must be a finite number ≥ 0 (N/m), got {}", spec.sigma),
            ));
        }
        let (a, b) = (usize::from(a), usize::from(b));
        if given[a * n + b] {
            return Err(bad(
                &place,
                format!(
                    "the pair '{}'–'{}' is given twice",
                    spec.phases[0], spec.phases[1]
                ),
            ));
        }
        given[a * n + b] = true;
        given[b * n + a] = true;
        sigma[a * n + b] = spec.sigma;
        sigma[b * n + a] = spec.sigma;
    }
    Ok(Tension { n, sigma })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bad(place: &str, message: String) -> SceneError {
        SceneError::Invalid {
            origin: "test".into(),
            place: place.into(),
            message,
        }
    }

    fn spec(a: &str, b: &str, sigma: f64) -> TensionSpec {
        TensionSpec {
            phases: [a.into(), b.into()],
            sigma,
        }
    }

    fn names() -> Vec<String> {
        ["air", "water", "oil"].map(String::from).to_vec()
    }

    /// Neumann's triangle: σ_wa = 0.0728 < 0.0275 + 0.0535 (hexadecane on water) balances;
    /// without the oil–water tension, or with ethanol's 0.022 against air and none against
    /// water, the largest σ is at least the sum of the others and nothing balances.
    #[test]
    fn triples_without_a_neumann_triangle_are_found() {
        let compile = |specs: &[TensionSpec]| compile_tension(specs, &names(), true, &bad).unwrap();
        let lens = compile(&[
            spec("water", "air", 0.0728),
            spec("oil", "air", 0.0275),
            spec("oil", "water", 0.0535),
        ]);
        assert!(lens.unbalanced_triples().is_empty());
        let spreading = compile(&[spec("water", "air", 0.0728), spec("oil", "air", 0.022)]);
        assert_eq!(spreading.unbalanced_triples(), vec![[0, 1, 2]]);
        // A single tension makes no junction pull: nothing to warn about.
        let single = compile(&[spec("water", "air", 0.0728)]);
        assert!(single.unbalanced_triples().is_empty());
    }

    #[test]
    fn pairs_are_symmetric_and_unlisted_pairs_have_none() {
        let t = compile_tension(
            &[spec("water", "air", 0.0728), spec("oil", "water", 0.03)],
            &names(),
            true,
            &bad,
        )
        .unwrap();
        assert_eq!(t.sigma(1, 0), 0.0728);
        assert_eq!(t.sigma(0, 1), 0.0728);
        assert_eq!(t.sigma(1, 2), 0.03);
        assert_eq!(t.sigma(0, 2), 0.0);
        assert_eq!(t.pairs(), vec![(0, 1, 0.0728), (1, 2, 0.03)]);
        assert!(t.any());
    }

    #[test]
    fn errors_name_the_entry() {
        let cases = [
            (
                vec![spec("water", "mud", 0.1)],
                "tension[0].phases[1]",
                "unknown phase 'mud'",
            ),
            (
                vec![spec("water", "water", 0.1)],
                "tension[0].phases",
                "twice",
            ),
            (vec![spec("water", "air", -1.0)], "tension[0].sigma", "≥ 0"),
            (
                vec![spec("water", "air", f64::NAN)],
                "tension[0].sigma",
                "finite",
            ),
            (
                vec![spec("water", "air", 0.07), spec("air", "water", 0.07)],
                "tension[1]",
                "given twice",
            ),
        ];
        for (specs, place, words) in cases {
            let err = compile_tension(&specs, &names(), true, &bad)
                .unwrap_err()
                .to_string();
            assert!(err.contains(place) && err.contains(words), "{err}");
        }
        let err = compile_tension(&[spec("water", "air", 0.07)], &names(), false, &bad)
            .unwrap_err()
            .to_string();
        assert!(err.contains("fluid solver"), "{err}");
    }
}
