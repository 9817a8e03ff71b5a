//! Scene files: JSON in and out, with one rule for the paths inside them.

use std::path::{Path, PathBuf};

use glint_core::RenderError;

use super::{Input, Scene, MAX_SCENE_BYTES, SCENE_VERSION};

impl Scene {
    /// Parses a scene from JSON, checking the version. Errors name the field
    /// (`lobe.kind: unknown lobe ...`).
    pub fn from_json(text: &str) -> Result<Scene, RenderError> {
        let mut de = serde_json::Deserializer::from_str(text);
        let scene: Scene = serde_path_to_error::deserialize(&mut de)
            .map_err(|e| RenderError::Scene(format!("bad scene JSON: {e}")))?;
        de.end()
            .map_err(|e| RenderError::Scene(format!("bad scene JSON: {e}")))?;
        let input_given = scene.has_meshes()
            && serde_json::from_str::<serde_json::Value>(text)
                .is_ok_and(|v| v.get("input").is_some());
        scene.meshes_only_unless(input_given).check_version()
    }

    /// A scene read with meshes and without an `input` key has no volume (the
    /// default phantom is for scenes of nothing else).
    fn meshes_only_unless(mut self, input_given: bool) -> Scene {
        if self.has_meshes() && !input_given {
            self.input = Input::None;
        }
        self
    }

    /// A scene from a parsed JSON value (e.g. a viewer's patched scene), checked like
    /// [`Scene::from_json`].
    pub fn from_value(value: serde_json::Value) -> Result<Scene, RenderError> {
        let input_given = value.get("input").is_some();
        let scene: Scene = serde_path_to_error::deserialize(value)
            .map_err(|e| RenderError::Scene(format!("bad scene JSON: {e}")))?;
        scene.meshes_only_unless(input_given).check_version()
    }

    fn check_version(self) -> Result<Scene, RenderError> {
        let scene = self;
        if scene.version == 0 || scene.version > SCENE_VERSION {
            return Err(RenderError::Scene(format!(
                "scene version {} is not supported (this glint reads version {SCENE_VERSION})",
                scene.version
            )));
        }
        Ok(scene)
    }

    /// Reads a scene file (at most [`MAX_SCENE_BYTES`]).
    pub fn from_json_file(path: &std::path::Path) -> Result<Scene, RenderError> {
        let file = |e: RenderError| RenderError::SceneFile {
            path: path.to_path_buf(),
            source: Box::new(e),
        };
        let meta = std::fs::metadata(path).map_err(|e| file(RenderError::Io(e)))?;
        if meta.len() > MAX_SCENE_BYTES {
            return Err(file(RenderError::Scene(format!(
                "{} bytes is too large for a scene (limit {MAX_SCENE_BYTES})",
                meta.len()
            ))));
        }
        let text = std::fs::read_to_string(path).map_err(|e| file(RenderError::Io(e)))?;
        Scene::from_json(&text).map_err(file)
    }

    /// The scene as pretty-printed JSON.
    pub fn to_json(&self) -> Result<String, RenderError> {
        serde_json::to_string_pretty(self).map_err(|e| RenderError::Scene(e.to_string()))
    }
}

impl Scene {
    /// Reads a scene file ([`Scene::from_json_file`]). Relative paths in it (the
    /// input, the meshes and their overlays) are relative to the file's directory, so a
    /// scene written beside its data renders from anywhere; absolute paths stay. The
    /// command line, the viewer and the Python module read scene files with this.
    pub fn load(path: &Path) -> Result<Scene, RenderError> {
        let mut scene = Scene::from_json_file(path)?;
        if let Some(dir) = path.parent() {
            for p in scene.paths_mut() {
                if p.is_relative() {
                    *p = dir.join(&*p);
                }
            }
            if let Some(t) = scene.table_file_mut() {
                if Path::new(t.as_str()).is_relative() {
                    *t = dir.join(t.as_str()).to_string_lossy().into_owned();
                }
            }
        }
        Ok(scene)
    }

    /// The label map's colour table when it names a file (not a built-in table).
    fn table_file_mut(&mut self) -> Option<&mut String> {
        let table = self.labels.as_mut()?.table.as_mut()?;
        let builtin = glint_labels::BUILTIN_TABLES
            .iter()
            .any(|b| b.eq_ignore_ascii_case(table));
        (!builtin).then_some(table)
    }

    /// Writes the scene as JSON to `path` atomically (no partial file on failure),
    /// with [absolute paths](Scene::with_absolute_paths), so it renders the same from
    /// anywhere ([`Scene::load`] reads it back).
    pub fn save(&self, path: &Path) -> Result<(), RenderError> {
        let json = self.with_absolute_paths()?.to_json()?;
        glint_io::write_atomic(path, |w| w.write_all(json.as_bytes())).map_err(RenderError::Write)
    }

    /// The scene with every relative path (the input, the meshes and their overlays)
    /// made absolute against the current directory.
    pub fn with_absolute_paths(&self) -> Result<Scene, RenderError> {
        let mut scene = self.clone();
        for p in scene.paths_mut() {
            *p = std::path::absolute(&*p).map_err(|e| {
                RenderError::Io(std::io::Error::new(
                    e.kind(),
                    format!("resolving {}: {e}", p.display()),
                ))
            })?;
        }
        if let Some(t) = scene.table_file_mut() {
            let abs = std::path::absolute(t.as_str()).map_err(|e| {
                RenderError::Io(std::io::Error::new(e.kind(), format!("resolving {t}: {e}")))
            })?;
            *t = abs.to_string_lossy().into_owned();
        }
        Ok(scene)
    }

    /// Every file path the scene names: its input, its meshes and their overlays.
    fn paths_mut(&mut self) -> Vec<&mut PathBuf> {
        let mut paths = Vec::new();
        if let Input::Path(p) = &mut self.input {
            paths.push(p);
        }
        if let Some(l) = &mut self.labels {
            paths.push(&mut l.path);
        }
        for m in &mut self.meshes {
            paths.push(&mut m.path);
            if let Some(o) = &mut m.overlay {
                paths.push(&mut o.path);
            }
        }
        paths
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{MeshSpec, Overlay};

    #[test]
    fn load_rebases_relative_paths_on_the_file_and_save_makes_them_absolute() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("study");
        std::fs::create_dir(&sub).unwrap();
        let mut mesh = MeshSpec::new("lh.gii");
        mesh.overlay = Some(Overlay::new("/abs/lh.sulc.gii"));
        let scene = Scene {
            input: Input::Path("brain.nii.gz".into()),
            meshes: vec![mesh],
            ..Scene::default()
        };
        let file = sub.join("scene.json");
        std::fs::write(&file, scene.to_json().unwrap()).unwrap();
        let loaded = Scene::load(&file).unwrap();
        assert_eq!(loaded.input, Input::Path(sub.join("brain.nii.gz")));
        assert_eq!(loaded.meshes[0].path, sub.join("lh.gii"));
        // Absolute paths stay as they are.
        let overlay = loaded.meshes[0].overlay.as_ref().unwrap();
        assert_eq!(overlay.path, PathBuf::from("/abs/lh.sulc.gii"));
        // Saved: every path absolute, and loading it back gives the same scene.
        let saved = dir.path().join("saved.json");
        scene.save(&saved).unwrap();
        let back = Scene::load(&saved).unwrap();
        let cwd = std::env::current_dir().unwrap();
        assert_eq!(back.input, Input::Path(cwd.join("brain.nii.gz")));
        assert_eq!(back.meshes[0].path, cwd.join("lh.gii"));
        assert_eq!(back, scene.with_absolute_paths().unwrap());
    }

    #[test]
    fn a_label_table_file_is_rebased_like_the_label_map_and_a_builtin_is_not() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("study");
        std::fs::create_dir(&sub).unwrap();
        let mut labels = crate::LabelSpec::new("seg/mask.nii.gz");
        labels.table = Some("tables/structures.csv".into());
        let scene = Scene {
            input: Input::Path("ct.nii.gz".into()),
            labels: Some(labels),
            ..Scene::default()
        };
        let file = sub.join("scene.json");
        std::fs::write(&file, scene.to_json().unwrap()).unwrap();
        let loaded = Scene::load(&file).unwrap();
        let l = loaded.labels.as_ref().unwrap();
        assert_eq!(l.path, sub.join("seg/mask.nii.gz"));
        let table = sub.join("tables/structures.csv");
        assert_eq!(l.table.as_deref(), Some(table.to_str().unwrap()));
        // Saved: absolute, like the map's path.
        let saved = dir.path().join("saved.json");
        scene.save(&saved).unwrap();
        let back = Scene::load(&saved).unwrap();
        let cwd = std::env::current_dir().unwrap();
        let table = cwd.join("tables/structures.csv");
        let l = back.labels.as_ref().unwrap();
        assert_eq!(l.table.as_deref(), Some(table.to_str().unwrap()));
        // A built-in table's name is not a path.
        let mut builtin = scene.clone();
        builtin.labels.as_mut().unwrap().table = Some("FreeSurfer".into());
        std::fs::write(&file, builtin.to_json().unwrap()).unwrap();
        let loaded = Scene::load(&file).unwrap();
        let l = loaded.labels.as_ref().unwrap();
        assert_eq!(l.table.as_deref(), Some("FreeSurfer"));
        let abs = builtin.with_absolute_paths().unwrap();
        assert_eq!(abs.labels.unwrap().table.as_deref(), Some("FreeSurfer"));
    }

    #[test]
    fn a_failed_save_leaves_no_file_and_names_it() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("no-such-dir").join("scene.json");
        let err = Scene::default().save(&target).unwrap_err();
        assert!(glint_io::one_line(&err).contains("scene.json"), "{err}");
        assert!(!target.exists());
        let err = Scene::load(&dir.path().join("missing.json")).unwrap_err();
        assert!(matches!(err, RenderError::SceneFile { .. }), "{err:?}");
    }
}
