//! Coupled runs at low resolution: Rayleigh–Taylor growth against linear theory, volume
//! conservation, determinism across thread counts.

use polyphase_coupling::{
    from_scene, interface_extent, AnyTracker, CoupledSim, Measured, RtLinear,
};
use polyphase_scenes::{builtin, Scene};
use polyphase_tracker::InterfaceTracker;

fn builtin_text(name: &str) -> &'static str {
    polyphase_scenes::BUILTIN
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, t)| *t)
        .unwrap()
}

/// Half the bubble-to-spike distance: the perturbation amplitude.
fn amplitude(sim: &CoupledSim<AnyTracker>) -> f64 {
    let (spike, bubble) = interface_extent(sim.tracker().mesh(), 0, Some(1), 1).unwrap();
    0.5 * (bubble - spike)
}

/// Runs the built-in Rayleigh–Taylor slab in its linear regime (amplitude 0.005 = 0.03/k,
/// 32 solver cells per wavelength, ν equal in both fluids) to t = 1.2 s and returns the mean
/// growth rate ln(a(t)/a₀)/t, measured and from the exact linear theory from rest
/// ([`RtLinear`]; for ν = 0, a/a₀ = cosh(√(Agk) t)); `every_step` advances the tracker every
/// solver step, else at the default `time.cfl`.
fn rayleigh_taylor_rate(nu: f64, every_step: bool) -> (f64, f64) {
    let frames = if every_step {
        "frames = 1\ncfl = 0.001"
    } else {
        "frames = 1"
    };
    let text = builtin_text("rayleigh_taylor")
        .replace("end = 3.0", "end = 1.2")
        .replace("frames = 30", frames)
        .replace("amplitude = -0.05", "amplitude = -0.005")
        .replace("viscosity = 3.0e-3", &format!("viscosity = {nu}"))
        .replace("viscosity = 9.0e-3", &format!("viscosity = {}", 3.0 * nu))
        .replace("gravity =", "max_dt = 0.02\ngravity =");
    let scene = Scene::parse(&text, "rt-linear").unwrap();
    let (mut sim, _) = from_scene(&scene).unwrap();
    let a0 = amplitude(&sim);
    let t = 1.2;
    sim.advance_to(t).unwrap();
    let k = 2.0 * std::f64::consts::PI;
    // Atwood (3 − 1)/(3 + 1) = 0.5, g = 1 in the scene.
    let theory = if nu > 0.0 {
        let rt = RtLinear {
            k,
            g: 1.0,
            heavy: (3.0, 3.0 * nu),
            light: (1.0, nu),
        };
        rt.amplitude_ratio(t)
    } else {
        ((0.5 * k).sqrt() * t).cosh()
    };
    ((amplitude(&sim) / a0).ln() / t, theory.ln() / t)
}

#[test]
fn rayleigh_taylor_growth_matches_viscous_linear_theory() {
    // ν = 0.01 m²/s slows the growth well below the inviscid theory (a/a₀ at 1.2 s: 2.90
    // against 4.25), so the check tells the viscous theory from the inviscid one. 5 % is the
    // issue's tolerance; measured +0.29 % (a/a₀ = 2.910 against 2.901).
    let (rate, theory) = rayleigh_taylor_rate(0.01, true);
    assert!(
        (rate - theory).abs() < 0.05 * theory,
        "viscous growth rate {rate} vs theory {theory}"
    );
}

#[test]
fn rayleigh_taylor_growth_matches_inviscid_linear_theory() {
    // Exact inviscid linear theory (tanh(kH) = tanh 2π ≈ 1 for these depths). Without
    // viscosity the interface is a vortex sheet, which the grid smears over a cell like a
    // numerical viscosity: measured −5.35 %, so 10 % here against the viscous cases' 5 %.
    let (rate, theory) = rayleigh_taylor_rate(0.0, true);
    assert!(
        (rate - theory).abs() < 0.10 * theory,
        "inviscid growth rate {rate} vs theory {theory}"
    );
}

#[test]
fn rayleigh_taylor_growth_at_the_default_tracker_cfl() {
    // The tracker advances every 8 of its cells of travel (here only at the end: the linear
    // flow moves under 0.03 m) and the solver samples its mesh advected to every step. The
    // issue's 5 % against viscous linear theory; measured +0.16 %.
    let (rate, theory) = rayleigh_taylor_rate(0.01, false);
    assert!(
        (rate - theory).abs() < 0.05 * theory,
        "viscous growth rate {rate} vs theory {theory} at the default cfl"
    );
}

/// The water column at low resolution, run to `end`, with or without the volume correction.
fn column_with(resolution: i64, end: f64, correction: bool) -> CoupledSim<AnyTracker> {
    let mut scene = builtin("dambreak_column")
        .unwrap()
        .unwrap()
        .with_overrides(Some(resolution), Some(1))
        .unwrap();
    scene.file.volume_correction = correction;
    let (mut sim, _) = from_scene(&scene).unwrap();
    sim.advance_to(end).unwrap();
    sim
}

/// The water column at low resolution, run to `end` as the scene says (corrected).
fn column(resolution: i64, end: f64) -> CoupledSim<AnyTracker> {
    column_with(resolution, end, true)
}

#[test]
fn column_collapse_conserves_phase_volumes() {
    let scene = builtin("dambreak_column").unwrap().unwrap();
    let scene = scene.with_overrides(Some(64), Some(1)).unwrap();
    let (sim0, _) = from_scene(&scene).unwrap();
    let start = sim0.tracker().phase_volumes();
    for correction in [false, true] {
        let sim = column_with(64, 0.2, correction);
        let end = sim.tracker().phase_volumes();
        for (a, b) in start.iter().zip(&end) {
            // The budget is 2 % per phase; the incompressible flow conserves volume
            // exactly, so what drifts is the tracker's resampling at 32 cells across the
            // column: measured −0.58 % of the water without the correction (the method's
            // own), −0.33 % with it (against frame 0, which the correction's exact target
            // lies above by the first contouring's shortfall).
            assert!(
                (b - a).abs() < 0.02 * a,
                "correction {correction}: {a} -> {b}"
            );
        }
        // The front has left the column (x = a = 0.1 m) and moved along the floor.
        let (_, front) = interface_extent(sim.tracker().mesh(), 1, None, 0).unwrap();
        assert!(front > 0.2, "surge front {front}");
    }
}

#[test]
fn one_and_two_threads_give_identical_results() {
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let sim = column(32, 0.1);
            (sim.tracker().mesh().clone(), sim.steps())
        })
    };
    let (a, sa) = run(1);
    let (b, sb) = run(2);
    assert_eq!(sa, sb);
    assert_eq!(a, b, "meshes differ between 1 and 2 threads");
}

#[test]
fn a_passive_scene_is_refused() {
    let scene = builtin("zalesak").unwrap().unwrap();
    let err = from_scene(&scene).err().unwrap().to_string();
    assert!(err.contains("passive"), "{err}");
}

/// Spike and bubble tips (lowest and highest point of the heavy–light interface) of the
/// built-in Atwood 0.5, Re 256 scene at tracker `resolution` (solver half that), at t = 2 s.
fn re256_tips(resolution: i64) -> (f64, f64) {
    let scene = builtin("rayleigh_taylor_re256")
        .unwrap()
        .unwrap()
        .with_overrides(Some(resolution), Some(1))
        .unwrap();
    let (mut sim, _) = from_scene(&scene).unwrap();
    sim.advance_to(2.0).unwrap();
    interface_extent(sim.tracker().mesh(), 1, Some(0), 1).unwrap()
}

#[test]
fn rayleigh_taylor_tips_converge_with_resolution() {
    // 16, 32 and 64 solver cells per wavelength: the change from 32 to 64 must be at most
    // half the change from 16 to 32 (first-order convergence or better, the bound).
    // Measured at t = 2 s: 0.43 for the spike, 0.21 for the bubble.
    let tips: Vec<(f64, f64)> = [128, 256, 512].into_iter().map(re256_tips).collect();
    for (name, pick) in [("spike", 0), ("bubble", 1)] {
        let at = |k: usize| if pick == 0 { tips[k].0 } else { tips[k].1 };
        let (coarse, fine) = ((at(1) - at(0)).abs(), (at(2) - at(1)).abs());
        assert!(fine <= 0.5 * coarse, "{name}: {tips:?}");
    }
    // The spike falls and the bubble rises from the start's ±0.1 (y = 1.9 and 2.1).
    assert!(tips[2].0 < 1.6 && tips[2].1 > 2.3, "{tips:?}");
}

/// The `tips` measurement of `text` (a Rayleigh–Taylor scene) after 0.5 s at tracker
/// resolution 32.
fn declared_tips(text: &str) -> polyphase_coupling::Measured {
    let scene = Scene::parse(text, "rt")
        .unwrap()
        .with_overrides(Some(32), Some(1))
        .unwrap();
    let (mut sim, _) = from_scene(&scene).unwrap();
    sim.advance_to(0.5).unwrap();
    let tips = scene.measures.iter().find(|m| m.name == "tips").unwrap();
    polyphase_coupling::measure(sim.tracker().mesh(), &tips.kind)
}

#[test]
fn a_renamed_scene_with_reordered_phases_measures_the_same() {
    // Measurements name their phases, so neither the scene's name nor the order of its phases
    // (which sets the phase ids) changes what they read.
    let text = builtin_text("rayleigh_taylor").replace("end = 3.0", "end = 0.5");
    let light = text.find("[[phases]]\nname = \"light\"").unwrap();
    let heavy = text.find("[[phases]]\nname = \"heavy\"").unwrap();
    let shapes = text.find("# Interface at").unwrap();
    let reordered = format!(
        "{}{}\n{}{}",
        &text[..light],
        &text[heavy..shapes].trim_end(),
        &text[light..heavy],
        &text[shapes..]
    )
    .replace("name = \"rayleigh_taylor\"", "name = \"my_copy\"");
    assert!(reordered.find("name = \"heavy\"") < reordered.find("name = \"light\""));
    let (a, b) = (declared_tips(&text), declared_tips(&reordered));
    let (Measured::Range(Some(a)), Measured::Range(Some(b))) = (a, b) else {
        panic!("tips missing");
    };
    // The same flow up to the order of floating-point sums over phases: 1e-9 of the box.
    assert!(
        (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9,
        "{a:?} vs {b:?}"
    );
    assert!(a.1 - a.0 > 0.0);
}
