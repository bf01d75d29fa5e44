//! `polyphase wedge SCENE --set PATH=V1,V2 … --out DIR`: a parameter wedge, one resolved and
//! validated scene per combination of the `--set` values (`DIR/<scene>-<k>/scene.toml`) and an
//! index (`DIR/wedge.json`). Every variant is validated before anything is written, so a bad
//! path or value leaves no folder behind. `polyphase run` runs any variant as usual, and
//! `polyphase submit wedge DIR` runs them all as a Slurm job array.

mod index;
mod set;

use std::fs;
use std::path::PathBuf;

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use polyphase_scenes::{Scene, SceneFile};
use toml::Value;

use crate::output::write_atomic;
pub use index::{Axis, Setting, Variant, WedgeIndex, FILE as INDEX_FILE};
use set::{set_path, SetAxis};

/// The most variants one wedge may have (a typo such as `1,2,…` repeated is caught early).
const MAX_VARIANTS: usize = 10_000;

/// Arguments of `polyphase wedge`.
#[derive(Args, Debug)]
pub struct WedgeArgs {
    /// Built-in scene name or path to a scene TOML file.
    pub scene: String,
    /// `PATH=V1,V2,…`: one axis of the wedge, a dotted path into the scene file
    /// (`phases.oil.viscosity`, `time.end`, `solver.cfl`; `phases.<name>` or `phases.<index>`
    /// picks an entry). Repeat for more axes; every combination is one variant. `resolution`
    /// keeps a coupled scene's tracker-to-solver ratio, like `polyphase run --resolution`.
    #[arg(long = "set", value_name = "PATH=V1,V2", required = true)]
    pub sets: Vec<String>,
    /// Folder for the variants; it must not exist yet, or be empty.
    #[arg(long)]
    pub out: PathBuf,
}

/// Builds, validates and writes the wedge.
pub fn wedge(args: &WedgeArgs) -> Result<()> {
    let axes = args
        .sets
        .iter()
        .map(|a| SetAxis::parse(a))
        .collect::<Result<Vec<_>>>()?;
    let count = axes
        .iter()
        .try_fold(1usize, |n, a| n.checked_mul(a.values.len()))
        .filter(|&n| n <= MAX_VARIANTS)
        .ok_or_else(|| anyhow!("the wedge has more than {MAX_VARIANTS} variants"))?;
    let base = polyphase_scenes::load(&args.scene)?;
    let doc = Value::try_from(&base.file).context("cannot serialise the scene")?;
    let mut variants = Vec::with_capacity(count);
    let mut texts = Vec::with_capacity(count);
    for k in 0..count {
        let name = format!("{}-{k}", base.file.name);
        let picks = combination(k, &axes);
        let (scene, v) = variant(&doc, &name, &axes, &picks)?;
        texts.push(scene.to_toml());
        variants.push(v);
    }
    let index = WedgeIndex {
        scene: args.scene.clone(),
        axes: axes
            .iter()
            .map(|a| Axis {
                path: a.path.clone(),
                values: a.values.iter().map(json_value).collect(),
            })
            .collect(),
        variants,
    };
    write(args, &index, &texts)?;
    for v in &index.variants {
        println!("{:<20} {}", v.name, v.label(" "));
    }
    println!(
        "wrote {} variants to {} (run one with `polyphase run {}`, all with `polyphase submit \
         wedge {}`)",
        count,
        args.out.display(),
        index.variants[0].scene_file(&args.out).display(),
        args.out.display()
    );
    Ok(())
}

/// The value index of every axis in variant `k`; the first axis varies slowest.
fn combination(mut k: usize, axes: &[SetAxis]) -> Vec<usize> {
    let mut picks = vec![0; axes.len()];
    for (i, axis) in axes.iter().enumerate().rev() {
        picks[i] = k % axis.values.len();
        k /= axis.values.len();
    }
    picks
}

/// One variant: the base document with its values written in, named `name`, validated.
fn variant(doc: &Value, name: &str, axes: &[SetAxis], picks: &[usize]) -> Result<(Scene, Variant)> {
    let mut doc = doc.clone();
    set_path(&mut doc, "name", Value::String(name.to_string()))?;
    let mut resolution = None;
    let mut settings = Vec::with_capacity(axes.len());
    for (axis, &i) in axes.iter().zip(picks) {
        let value = axis.values[i].clone();
        settings.push(Setting {
            path: axis.path.clone(),
            value: json_value(&value),
        });
        if axis.path == "resolution" {
            let r = value
                .as_integer()
                .ok_or_else(|| anyhow!("--set {}: resolution must be an integer", axis.arg))?;
            resolution = Some(r);
        } else {
            set_path(&mut doc, &axis.path, value).with_context(|| format!("--set {}", axis.arg))?;
        }
    }
    let variant = Variant {
        name: name.to_string(),
        settings,
    };
    let origin = format!("variant {name} ({})", variant.label(", "));
    let file: SceneFile = doc
        .try_into()
        .map_err(|e: toml::de::Error| anyhow!("{origin}: {}", e.message()))?;
    let scene = Scene::from_file(file, &origin)?;
    let scene = match resolution {
        Some(r) => scene
            .with_overrides(Some(r), None)
            .with_context(|| format!("{origin}: resolution {r}"))?,
        None => scene,
    };
    Ok((scene, variant))
}

/// A TOML value as JSON (for the index).
fn json_value(v: &Value) -> serde_json::Value {
    serde_json::to_value(v).unwrap_or(serde_json::Value::Null)
}

/// Writes every variant's `scene.toml` and then the index, into a new or empty folder.
fn write(args: &WedgeArgs, index: &WedgeIndex, texts: &[String]) -> Result<()> {
    let out = &args.out;
    if let Ok(mut entries) = fs::read_dir(out) {
        if entries.next().is_some() {
            bail!(
                "{} is not empty; a wedge goes into a new folder",
                out.display()
            );
        }
    }
    for (v, text) in index.variants.iter().zip(texts) {
        let dir = out.join(&v.name);
        fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
        write_atomic(&v.scene_file(out), text.as_bytes())?;
    }
    let json = serde_json::to_string_pretty(index)?;
    write_atomic(&out.join(index::FILE), json.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_axis_varies_slowest() {
        let axes = [
            SetAxis::parse("a=1,2").expect("axis"),
            SetAxis::parse("b=1,2,3").expect("axis"),
        ];
        let all: Vec<Vec<usize>> = (0..6).map(|k| combination(k, &axes)).collect();
        assert_eq!(
            all,
            [[0, 0], [0, 1], [0, 2], [1, 0], [1, 1], [1, 2]].map(Vec::from)
        );
    }
}
