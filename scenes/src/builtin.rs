//! Built-in scenes: TOML files shipped in `scenes/builtin/`, which users can copy and edit.

use crate::error::SceneError;
use crate::scene::Scene;

/// (name, TOML text) of every built-in scene, in the order `polyphase scenes` lists them.
pub const BUILTIN: &[(&str, &str)] = &[
    ("zalesak", include_str!("../builtin/zalesak.toml")),
    ("enright", include_str!("../builtin/enright.toml")),
    ("enright6", include_str!("../builtin/enright6.toml")),
    ("nested", include_str!("../builtin/nested.toml")),
    ("vortex4", include_str!("../builtin/vortex4.toml")),
    ("circle3", include_str!("../builtin/circle3.toml")),
    (
        "circle3_rotate",
        include_str!("../builtin/circle3_rotate.toml"),
    ),
    ("checker", include_str!("../builtin/checker.toml")),
    ("dambreak", include_str!("../builtin/dambreak.toml")),
    (
        "dambreak_column",
        include_str!("../builtin/dambreak_column.toml"),
    ),
    (
        "rayleigh_taylor",
        include_str!("../builtin/rayleigh_taylor.toml"),
    ),
    (
        "rayleigh_taylor_re256",
        include_str!("../builtin/rayleigh_taylor_re256.toml"),
    ),
    ("fall", include_str!("../builtin/fall.toml")),
    ("droplet", include_str!("../builtin/droplet.toml")),
    ("lens", include_str!("../builtin/lens.toml")),
    ("balls", include_str!("../builtin/balls.toml")),
    (
        "balls_tension",
        include_str!("../builtin/balls_tension.toml"),
    ),
    ("drop_pool", include_str!("../builtin/drop_pool.toml")),
    ("pool", include_str!("../builtin/pool.toml")),
    ("viscous", include_str!("../builtin/viscous.toml")),
    ("merge2", include_str!("../builtin/merge2.toml")),
    (
        "merge2_reverse",
        include_str!("../builtin/merge2_reverse.toml"),
    ),
    ("merge_same", include_str!("../builtin/merge_same.toml")),
    ("spheres25", include_str!("../builtin/spheres25.toml")),
    ("cyclic", include_str!("../builtin/cyclic.toml")),
    ("noise4", include_str!("../builtin/noise4.toml")),
    ("mcf_t1", include_str!("../builtin/mcf_t1.toml")),
    ("mcf_t2", include_str!("../builtin/mcf_t2.toml")),
    (
        "double_bubble",
        include_str!("../builtin/double_bubble.toml"),
    ),
    ("foam", include_str!("../builtin/foam.toml")),
];

/// (name, bytes) of the OBJ files the built-in scenes use (`file = "NAME"` in a built-in scene,
/// `file = "builtin:NAME"` in any scene); the same files sit beside the TOML in `scenes/builtin/`.
pub const BUILTIN_FILES: &[(&str, &[u8])] = &[("ring.obj", include_bytes!("../builtin/ring.obj"))];

/// The scene `polyphase run` uses when none is named.
pub const DEFAULT_SCENE: &str = "dambreak";

/// A built-in scene by name.
pub fn builtin(name: &str) -> Option<Result<Scene, SceneError>> {
    BUILTIN
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(n, text)| Scene::parse(text, &format!("builtin:{n}")))
}

/// A built-in scene name, or else a path to a scene file.
pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
    if let Some(scene) = builtin(name_or_path) {
        return scene;
    }
    let path = std::path::Path::new(name_or_path);
    if !path.exists() {
        return Err(SceneError::Unknown {
            name: name_or_path.to_string(),
            known: BUILTIN
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", "),
        });
    }
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: name_or_path.to_string(),
        source,
    })?;
    Scene::parse(&text, name_or_path)
}

#[cfg(test)]
mod tests {
    use polyphase_tracker::front::params::{FrontParams, PASSIVE_CFL};

    use super::*;
    use crate::{TrackerKind, TrackerSpec};

    #[test]
    fn every_builtin_parses_and_round_trips() {
        for (name, _) in BUILTIN {
            let scene = builtin(name).unwrap().unwrap();
            assert_eq!(scene.file.name, *name);
            // The resolved TOML reloads to the same scene (every default written out).
            let again = Scene::parse(&scene.to_toml(), "resolved").unwrap();
            assert_eq!(again.file, scene.file, "{name}");
            assert_eq!(again.grid, scene.grid, "{name}");
        }
    }

    #[test]
    fn the_tracker_is_a_kind_or_a_table_and_resolves_to_the_table() {
        let good = BUILTIN[0].1;
        let short = good.replace("background = ", "tracker = \"front\"\nbackground = ");
        let table = format!("{good}\n[tracker]\nkind = \"front\"\n[tracker.front]\ncfl = 0.5\n");
        let short = Scene::parse(&short, "short").unwrap();
        let table = Scene::parse(&table, "table").unwrap();
        assert_eq!(short.file.tracker.kind, TrackerKind::Front);
        // zalesak is passive: the unset step bound resolves to the passive one.
        let defaults = FrontParams::default();
        let resolved = FrontParams {
            cfl: Some(PASSIVE_CFL),
            exact_start: Some(false),
            ..defaults.clone()
        };
        assert_eq!(short.file.tracker.front.as_ref(), Some(&resolved));
        let front = table.file.tracker.front.clone().unwrap();
        assert_eq!(front.cfl, Some(0.5));
        assert_eq!(front.max_edge, defaults.max_edge);
        let again = Scene::parse(&table.to_toml(), "resolved").unwrap();
        assert_eq!(again.file.tracker, table.file.tracker);
        // Half the travel per step takes twice the steps, up to the rounding up of the count.
        let h = short.grid.h;
        let (a, b) = (short.steps_per_frame(h), short.steps_per_frame(0.5 * h));
        assert!(b == 2 * a || b == 2 * a - 1, "{a} vs {b}");
        assert_eq!(
            Scene::parse(good, "contour").unwrap().file.tracker,
            TrackerSpec::default()
        );
    }

    /// The resolved front-tracker parameters of built-in `name` with `extra` appended, run
    /// with the front tracker.
    fn front_params(name: &str, extra: &str) -> FrontParams {
        let text = format!("{}{extra}", builtin_text(name));
        let scene = Scene::parse(&text, name).unwrap();
        let scene = scene.with_tracker(TrackerKind::Front).unwrap();
        scene.file.tracker.front.unwrap()
    }

    /// Passive runs step 3 L by default (the paper's code's step), coupled runs and
    /// mesh-driven flows 1 L, and a scene's own value is kept.
    #[test]
    fn the_front_step_bound_defaults_by_what_moves_the_mesh() {
        let cfl = |name: &str, extra: &str| front_params(name, extra).cfl;
        assert_eq!(cfl("enright", ""), Some(PASSIVE_CFL));
        assert_eq!(cfl("dambreak_column", ""), Some(1.0));
        assert_eq!(cfl("merge2", ""), Some(1.0));
        let own = "\n[tracker]\nkind = \"front\"\n[tracker.front]\ncfl = 2.0\n";
        assert_eq!(cfl("enright", own), Some(2.0));
    }

    /// The front tracker's start is put on the exact initial interface where surface tension
    /// reads its curvature, and left as remeshed elsewhere unless the scene asks.
    #[test]
    fn the_exact_start_defaults_on_with_surface_tension() {
        let exact = |name: &str, extra: &str| front_params(name, extra).exact_start;
        assert_eq!(exact("droplet", ""), Some(true));
        assert_eq!(exact("dambreak_column", ""), Some(false));
        let own = "\n[tracker]\nkind = \"front\"\n[tracker.front]\nexact_start = true\n";
        assert_eq!(exact("enright", own), Some(true));
    }

    #[test]
    fn slab_scenes_are_two_cells_thick() {
        let s = builtin("vortex4").unwrap().unwrap();
        assert_eq!(s.grid.dims, [256, 256, 2]);
        assert!((s.file.domain.hi[2] - 2.0 / 256.0).abs() < 1e-15);
    }

    #[test]
    fn bad_scenes_name_the_problem_and_place() {
        let good = BUILTIN[0].1;
        let cases: Vec<(String, &str)> = vec![
            (
                good.replace("resolution = 64", "resolution = -3"),
                "resolution",
            ),
            (
                good.replace("phase = \"blue\"", "phase = \"green\""),
                "shapes[1].phase",
            ),
            (
                good.replace("radius = 0.15\n\n# Upper", "radius = nan\n\n# Upper"),
                "shapes[0].radius",
            ),
            (good.replace("end = 1.0\n", ""), "missing field `end`"),
            (
                good.replace("density = 1.2", "density = -1.2"),
                "phases[0].density",
            ),
            (
                good.replace("frames = 24", "frames = 24\nfrmes = 3"),
                "unknown field `frmes`",
            ),
            (
                good.replace("kind = \"box\"", "kind = \"torus\""),
                "shapes[2].kind",
            ),
            (
                good.replace("[1.0, 1.0, 1.0]", "[1.0, inf, 1.0]"),
                "domain.hi[1]",
            ),
            (
                good.replace("background = ", "tracker = \"fronts\"\nbackground = "),
                "unknown variant `fronts`",
            ),
            (
                format!("{good}\n[tracker]\nkind = \"front\"\n[tracker.front]\nmax_edges = 2.0\n"),
                "unknown field `max_edges`",
            ),
            (
                format!("{good}\n[tracker]\nkind = \"front\"\n[tracker.front]\nmin_edge = 0.9\n"),
                "tracker.front: need 0 < min_edge and 2 min_edge < max_edge",
            ),
            (
                format!("{good}\n[tracker.front]\ncfl = 0.5\n"),
                "tracker.front: is read only by the front tracker",
            ),
        ];
        for (text, expect) in cases {
            let err = Scene::parse(&text, "test.toml").unwrap_err().to_string();
            assert!(err.starts_with("test.toml: "), "{err}");
            assert!(err.contains(expect), "expected '{expect}' in: {err}");
            assert!(!err.contains('\n'), "one line: {err}");
        }
    }

    #[test]
    fn coupled_scenes_get_a_nested_solver_grid() {
        let s = builtin("dambreak_column").unwrap().unwrap();
        let g = s.solver_grid.unwrap();
        assert_eq!(s.grid.dims, [128, 64, 2]);
        assert_eq!(g.dims, [64, 32, 1]);
        // Both grids cover the same box.
        assert!((g.upper() - s.grid.upper()).length() < 1e-12);
        // The resolution override keeps the tracker-to-solver ratio.
        let low = s.with_overrides(Some(32), None).unwrap();
        assert_eq!(low.solver_grid.unwrap().dims, [16, 8, 1]);
        assert!(!builtin("zalesak").unwrap().unwrap().is_coupled());
    }

    #[test]
    fn bad_coupled_scenes_name_the_problem_and_place() {
        let good = builtin_text("dambreak");
        let cases: Vec<(String, &str)> = vec![
            (
                good.replace("density = 800.0", "density = 0.0"),
                "phases[2].density",
            ),
            (
                good.replace("[solver]\nresolution = 32", "[solver]\nresolution = 24"),
                "solver.resolution",
            ),
            (good.replace("cfl = 1.0", "cfl = -1.0"), "solver.cfl"),
            (
                good.replace("[solver]", "[solver]\nmax_dt = 0.0"),
                "solver.max_dt",
            ),
            (
                good.replace("field = \"fluid\"", "field = \"still\""),
                "solver: only a coupled scene",
            ),
        ];
        for (text, expect) in cases {
            let err = Scene::parse(&text, "test.toml").unwrap_err().to_string();
            assert!(err.contains(expect), "expected '{expect}' in: {err}");
        }
    }

    #[test]
    fn viscous_ring_is_the_shipped_obj_and_keeps_its_volume() {
        let s = builtin("viscous").unwrap().unwrap();
        let ring = s.file.shapes.iter().find(|s| s.kind == "mesh").unwrap();
        assert_eq!(ring.file.as_deref(), Some("builtin:ring.obj"));
        // The ring alone, by the quadrature at depth 5 (h = 1/512 of the 1 m domain) against
        // the divergence theorem on the OBJ.
        let shapes = s.initial.shapes.iter();
        let only = crate::InitialPhases {
            background: 0,
            shapes: shapes
                .filter(|x| matches!(x.primitive, crate::shapes::Primitive::Mesh(_)))
                .cloned()
                .collect(),
            foam: None,
        };
        let v = crate::volume::reference_volumes(&only, &s.grid, s.file.phases.len(), 5);
        let syrup = s.phase_names().iter().position(|n| n == "syrup").unwrap();
        let mesh = crate::obj::parse_obj(BUILTIN_FILES[0].1, 1.0, glam::DVec3::ZERO).unwrap();
        let exact = mesh.signed_volume();
        // O(h²) per unit area (volume.rs): ring area ≈ 4π²·0.12·0.05 ≈ 0.24, h² ≈ 3.8e-6:
        // ≈ 9e-7 absolute, 1.6e-4 of the 5.7e-3 m³; twice that leaves margin.
        assert!(
            (v[syrup] - exact).abs() / exact < 3.2e-4,
            "{v:?} vs {exact}"
        );
    }

    fn builtin_text(name: &str) -> &'static str {
        BUILTIN.iter().find(|(n, _)| *n == name).unwrap().1
    }

    #[test]
    fn unknown_name_lists_the_builtins() {
        let err = load("no-such-scene").unwrap_err().to_string();
        assert!(
            err.contains("zalesak") && err.contains("no-such-scene"),
            "{err}"
        );
    }
}
