//! Where a mesh shape's OBJ comes from: a path relative to the scene file's folder, an
//! absolute path, or `builtin:NAME` for one shipped with the built-in scenes. The resolved
//! name (absolute path or `builtin:NAME`) goes into the resolved scene, so a run folder's
//! `scene.toml` reloads from anywhere.

use std::path::{Path, PathBuf};

use crate::builtin::BUILTIN_FILES;

/// Prefix of the names of OBJ files shipped with the built-in scenes.
pub const BUILTIN_PREFIX: &str = "builtin:";

/// What relative OBJ paths in a scene are relative to.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneBase {
    /// A built-in scene: relative names are the files shipped beside it.
    Builtin,
    /// A scene file's folder.
    Folder(PathBuf),
}

impl SceneBase {
    /// The base of a scene whose errors start with `origin` (`builtin:NAME` or a file path).
    pub fn from_origin(origin: &str) -> Self {
        if origin.starts_with(BUILTIN_PREFIX) {
            SceneBase::Builtin
        } else {
            SceneBase::Folder(
                Path::new(origin)
                    .parent()
                    .map_or_else(PathBuf::new, Path::to_path_buf),
            )
        }
    }
}

/// The resolved name of `file` and its bytes; the error message names the file and why.
pub fn read(file: &str, base: &SceneBase) -> Result<(String, Vec<u8>), String> {
    let shipped = match (file.strip_prefix(BUILTIN_PREFIX), base) {
        (Some(name), _) => Some(name),
        (None, SceneBase::Builtin) if Path::new(file).is_relative() => Some(file),
        _ => None,
    };
    if let Some(name) = shipped {
        let known = || {
            BUILTIN_FILES
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", ")
        };
        return BUILTIN_FILES
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(n, bytes)| (format!("{BUILTIN_PREFIX}{n}"), bytes.to_vec()))
            .ok_or_else(|| format!("{file}: no such built-in file (built-in: {})", known()));
    }
    let path = match base {
        SceneBase::Folder(dir) if Path::new(file).is_relative() => dir.join(file),
        _ => PathBuf::from(file),
    };
    let bytes = std::fs::read(&path)
        .map_err(|e| format!("{}: cannot read OBJ file: {e}", path.display()))?;
    // Absolute, so the resolved scene does not depend on the folder it is read from.
    let absolute = std::path::absolute(&path).unwrap_or(path);
    Ok((absolute.to_string_lossy().into_owned(), bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_names_resolve_to_the_shipped_files() {
        let here = SceneBase::from_origin("some/dir/scene.toml");
        assert_eq!(here, SceneBase::Folder(PathBuf::from("some/dir")));
        // `builtin:` works from any scene; a bare name only from a built-in one.
        let (name, bytes) = read("builtin:ring.obj", &here).unwrap();
        assert_eq!(name, "builtin:ring.obj");
        assert_eq!(bytes, BUILTIN_FILES[0].1);
        let base = SceneBase::from_origin("builtin:viscous");
        assert_eq!(read("ring.obj", &base).unwrap().0, "builtin:ring.obj");
        let err = read("builtin:nope.obj", &here).unwrap_err();
        assert!(
            err.contains("nope.obj") && err.contains("ring.obj"),
            "{err}"
        );
        let err = read("ring.obj", &here).unwrap_err();
        assert!(
            err.contains("some/dir/ring.obj") && err.contains("cannot read"),
            "{err}"
        );
    }
}
