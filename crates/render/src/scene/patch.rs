//! Partial updates of a scene, as the viewer's clients and the Python module send them.

use serde_json::{Map, Value};

use glint_core::RenderError;

use super::Scene;

/// Scene fields that are objects [`Scene::patch`] merges field by field.
pub const MERGED_FIELDS: [&str; 4] = ["camera", "lobe", "material", "lighting"];

impl Scene {
    /// The scene with the exact lobe (`cos^n`) and everything else as it is: the
    /// reference the other lobes are compared with (`glint compare`, the viewer's split
    /// view, Python's `compare`).
    pub fn with_exact_lobe(&self) -> Scene {
        let mut s = self.clone();
        s.lobe.kind = glint_lobe::LobeKind::Exact.into();
        s
    }

    /// The scene with the fields of `patch` (scene JSON's field names and values)
    /// applied: the objects of [`MERGED_FIELDS`] (`camera`, `lobe`, `material`,
    /// `lighting`) merged field by field, every other field replaced; `null` gives a field its default
    /// (inside a merged object, for its optional fields). The result is checked as a
    /// scene file is ([`Scene::from_value`]): unknown fields and bad values are errors
    /// that name the field.
    ///
    /// ```
    /// use glint_render::Scene;
    /// let scene = Scene::default();
    /// let patch = serde_json::json!({"camera": {"zoom": 2.0}, "lobe": {"n": 40}, "size": [64, 48]});
    /// let next = scene.patch(patch.as_object().unwrap()).unwrap();
    /// assert_eq!((next.camera.zoom, next.camera.view), (2.0, scene.camera.view));
    /// assert_eq!((next.lobe.n, next.lobe.kind), (Some(40.0), scene.lobe.kind));
    /// assert_eq!(next.size, [64, 48]);
    /// assert!(scene.patch(serde_json::json!({"colour": 1}).as_object().unwrap()).is_err());
    /// ```
    pub fn patch(&self, patch: &Map<String, Value>) -> Result<Scene, RenderError> {
        let mut doc = serde_json::to_value(self).map_err(|e| RenderError::Scene(e.to_string()))?;
        let Value::Object(fields) = &mut doc else {
            return Err(RenderError::Scene(
                "a scene serialises to a JSON object".into(),
            ));
        };
        for (key, value) in patch {
            match (fields.get_mut(key), value) {
                (_, Value::Null) => {
                    fields.remove(key);
                }
                (Some(Value::Object(current)), Value::Object(changes))
                    if MERGED_FIELDS.contains(&key.as_str()) =>
                {
                    for (k, v) in changes {
                        current.insert(k.clone(), v.clone());
                    }
                }
                _ => {
                    fields.insert(key.clone(), value.clone());
                }
            }
        }
        Scene::from_value(doc)
    }
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::*;
    use crate::{Input, LobeSpec, Phantom};

    fn patched(scene: &Scene, patch: Value) -> Result<Scene, RenderError> {
        scene.patch(patch.as_object().unwrap())
    }

    #[test]
    fn merged_objects_keep_their_other_fields_and_null_restores_defaults() {
        let scene = Scene {
            lobe: LobeSpec {
                n: Some(80.0),
                v: 3,
                ..LobeSpec::default()
            },
            step: 0.25,
            ..Scene::default()
        };
        let next = patched(&scene, json!({"lobe": {"kind": "exact"}, "step": null})).unwrap();
        assert_eq!(next.lobe.kind.name(), "exact");
        // The lobe's other fields stay; the top-level null restores the default step.
        assert_eq!((next.lobe.n, next.lobe.v), (Some(80.0), 3));
        assert_eq!(next.step, Scene::default().step);
        // A null inside a merged object resets an optional field.
        let next = patched(&scene, json!({"lobe": {"n": null}})).unwrap();
        assert_eq!(next.lobe.n, None);
        // Fields outside the merged objects are replaced whole.
        let next = patched(
            &scene,
            json!({"lights": [{"azimuth": 30, "elevation": 10}]}),
        )
        .unwrap();
        assert_eq!(next.lights.len(), 1);
        assert_eq!(next.lights[0].azimuth, 30.0);
    }

    #[test]
    fn bad_patches_name_the_field() {
        let scene = Scene::default();
        let err = patched(&scene, json!({"camera": {"zoom": "big"}})).unwrap_err();
        assert!(err.to_string().contains("camera.zoom"), "{err}");
        let err = patched(&scene, json!({"lobe": {"kind": "lambert"}})).unwrap_err();
        assert!(err.to_string().contains("lobe.kind"), "{err}");
        assert!(patched(&scene, json!({"nonsense": 1})).is_err());
        assert!(patched(&scene, json!({"version": 99})).is_err());
    }

    #[test]
    fn input_is_replaced_whole() {
        let scene = Scene::default();
        let next = patched(
            &scene,
            json!({"input": {"phantom": {"name": "shepp-logan", "size": 16}}}),
        )
        .unwrap();
        assert_eq!(
            next.input,
            Input::Phantom {
                name: Phantom::SheppLogan,
                size: 16
            }
        );
    }
}
