//! What every input of a study gets: one scene, the views of its mosaic, slices or not.

use std::path::Path;

use glint_io::ReadOptions;
use glint_render::{Input, Scene, View};
use serde_json::json;
use sha2::{Digest, Sha256};

use crate::BatchError;

/// The version of what a job writes (files, row fields, pictures). Part of
/// [`Spec::key`]: a glint that writes them differently redoes every input.
pub const FORMAT_VERSION: u32 = 1;

/// What a study makes of each input.
#[derive(Clone, Debug, PartialEq)]
pub struct Spec {
    /// The scene of every view (its `input` is replaced by each input's path, its
    /// camera's `view` by each view's).
    pub scene: Scene,
    /// The views of the mosaic, left to right.
    pub views: Vec<View>,
    /// Whether to make the three orthogonal slices.
    pub slices: bool,
    /// Refuse what lenient readers accept with a note (`glint render --strict`).
    pub strict: bool,
    /// Also write the mosaic's linear radiance as 32-bit float OpenEXR
    /// ([`MOSAIC_EXR_FILE`](crate::MOSAIC_EXR_FILE), beside the PNG the report shows).
    pub exr: bool,
}

impl Spec {
    /// A spec of `scene` (its `derived` part dropped), lenient reading.
    pub fn new(scene: Scene, views: Vec<View>, slices: bool) -> Spec {
        Spec {
            scene: Scene {
                derived: None,
                ..scene
            },
            views,
            slices,
            strict: false,
            exr: false,
        }
    }

    /// Refuses a spec with no view.
    pub fn check(&self) -> Result<(), BatchError> {
        if self.views.is_empty() {
            return Err(BatchError::Spec("no view: give at least one".into()));
        }
        Ok(())
    }

    /// How inputs are read.
    pub fn read_options(&self) -> ReadOptions {
        ReadOptions {
            strict: self.strict,
            ..ReadOptions::default()
        }
    }

    /// `sha256:` and the SHA-256 of everything that decides an input's outputs
    /// besides its bytes: [`FORMAT_VERSION`], the scene (without its input), the
    /// views, slices and strictness. The scene is serialised in its fields' declared
    /// order, so the key does not depend on how serde_json was built.
    pub fn key(&self) -> Result<String, BatchError> {
        let scene = Scene {
            input: Input::None,
            derived: None,
            ..self.scene.clone()
        };
        let scene = serde_json::to_string(&scene)
            .map_err(|e| BatchError::Spec(format!("the scene does not serialise: {e}")))?;
        let views: Vec<&str> = self.views.iter().map(|v| v.name()).collect();
        let mut text = format!(
            "glint-batch {FORMAT_VERSION}\nscene {scene}\nviews {}\nslices {}\nstrict {}\n",
            views.join(","),
            self.slices,
            self.strict
        );
        // Only when asked: the keys of PNG-only studies stay what they were.
        if self.exr {
            text.push_str("exr true\n");
        }
        Ok(format!("sha256:{:x}", Sha256::digest(text.as_bytes())))
    }

    /// The scene of one view of one input: the spec's scene patched
    /// ([`Scene::patch`]) with the input's path and the view.
    pub fn scene_for(&self, path: &Path, view: View) -> Result<Scene, BatchError> {
        let path = path.to_str().ok_or_else(|| {
            BatchError::Spec(format!("{}: the path is not UTF-8", path.display()))
        })?;
        let patch = json!({
            "input": {"path": path},
            "camera": {"view": view.name()},
        });
        let map = patch.as_object().expect("a JSON object literal");
        Ok(self.scene.patch(map)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_key_follows_what_changes_the_outputs_and_not_the_input() {
        let base = Spec::new(Scene::default(), vec![View::Left, View::Anterior], false);
        let key = base.key().unwrap();
        assert!(key.starts_with("sha256:") && key.len() == 7 + 64, "{key}");
        let other_input = Spec {
            scene: Scene {
                input: Input::Path("/elsewhere.nii".into()),
                ..Scene::default()
            },
            ..base.clone()
        };
        assert_eq!(other_input.key().unwrap(), key);
        let changes = [
            Spec {
                views: vec![View::Anterior, View::Left],
                ..base.clone()
            },
            Spec {
                slices: true,
                ..base.clone()
            },
            Spec {
                strict: true,
                ..base.clone()
            },
            Spec {
                exr: true,
                ..base.clone()
            },
            Spec {
                scene: Scene {
                    size: [64, 64],
                    ..Scene::default()
                },
                ..base.clone()
            },
        ];
        for spec in changes {
            assert_ne!(spec.key().unwrap(), key, "{spec:?}");
        }
    }

    #[test]
    fn a_view_scene_has_the_input_and_the_view() {
        let spec = Spec::new(
            Scene {
                size: [40, 30],
                ..Scene::default()
            },
            vec![View::Superior],
            false,
        );
        let scene = spec
            .scene_for(Path::new("/data/a.nii"), View::Superior)
            .unwrap();
        assert_eq!(scene.input, Input::Path("/data/a.nii".into()));
        assert_eq!(scene.camera.view, View::Superior);
        assert_eq!(scene.size, [40, 30]);
        let none = Spec::new(Scene::default(), vec![], false);
        assert!(none.check().is_err());
    }
}
