//! Partial updates of a scene, as the viewer's clients and the Python module send them.

use serde_json::{Map, Value};

use glint_core::{RenderError, RenderMode};
use glint_volume::{TransferFunction, WindowLevel};

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
    /// (inside a merged object too: `{"lighting": {"area_lights": null}}` clears the
    /// list). The result is checked as a
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
                        // A null gives the field its default, as at the top level
                        // (a list such as `lighting.area_lights` has no null).
                        if v.is_null() {
                            current.remove(k);
                        } else {
                            current.insert(k.clone(), v.clone());
                        }
                    }
                }
                _ => {
                    fields.insert(key.clone(), value.clone());
                }
            }
        }
        let mut next = Scene::from_value(doc)?;
        let sets = |k: &str| patch.get(k).is_some_and(|v| !v.is_null());
        for key in patch.keys().filter(|k| sets(k)) {
            next.follow_edit(key, &sets);
        }
        Ok(next)
    }

    /// Classifies the scene with the preset `name`: its transfer function replaces
    /// the scene's own (the rule of `glint render --preset`, the viewer's preset menu
    /// and a `preset` patch).
    pub fn set_preset(&mut self, name: impl Into<String>) {
        self.preset = Some(name.into());
        self.follow_edit("preset", &|_| false);
    }

    /// Windows the scene's transfer function (the preset's or its own) at `wl`
    /// ([`Scene::window_level`](Scene#structfield.window_level)); `None` shows the
    /// function as it is. Checked here: a width that is not positive is refused.
    pub fn set_window_level(&mut self, wl: Option<WindowLevel>) -> Result<(), RenderError> {
        if let Some(w) = &wl {
            w.validate()?;
        }
        self.window_level = wl;
        Ok(())
    }

    /// Classifies the scene with `tf`, which replaces its preset's.
    pub fn set_transfer_function(&mut self, tf: TransferFunction) {
        self.transfer_function = Some(tf);
        self.follow_edit("transfer_function", &|_| false);
    }

    /// Renders the scene in `mode`; a mode that draws no isosurface (not `iso` or
    /// `surface`) forgets the iso value, so the next iso scene takes its default.
    pub fn set_mode(&mut self, mode: RenderMode) {
        self.mode = mode;
        self.follow_edit("mode", &|_| false);
    }

    /// The scene-editing rules, written once: what setting `field` clears, unless
    /// the same edit sets that too (`also_set`).
    fn follow_edit(&mut self, field: &str, also_set: &dyn Fn(&str) -> bool) {
        // A new classification starts from its own window.
        if matches!(field, "preset" | "transfer_function") && !also_set("window_level") {
            self.window_level = None;
        }
        // A preset brings its sampling: pre-integrated when its opacity is steep
        // (moiré otherwise, issue 42 item 6d); an unknown name is refused later.
        if field == "preset" && !also_set("sampling") {
            if let Some(p) = (self.preset.as_deref()).and_then(|n| glint_volume::preset(n).ok()) {
                self.sampling = p.sampling();
            }
        }
        match field {
            "preset" if !also_set("transfer_function") => self.transfer_function = None,
            "transfer_function" if !also_set("preset") => self.preset = None,
            "mode"
                if !also_set("iso")
                    && !matches!(self.mode, RenderMode::Iso | RenderMode::Surface) =>
            {
                self.iso = None
            }
            _ => {}
        }
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
        // And a list's, which has no null: the area lights set, then cleared.
        let lit = json!({"lighting": {"area_lights": [{"shape": {"sphere": {"radius": 20}}, "position": [0, 0, 300], "radiance": [5, 5, 5]}]}});
        let lit = patched(&scene, lit).unwrap();
        assert_eq!(lit.lighting.area_lights.len(), 1);
        let cleared = patched(&lit, json!({"lighting": {"area_lights": null}})).unwrap();
        assert!(cleared.lighting.area_lights.is_empty());
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
    fn a_preset_replaces_the_transfer_function_and_a_flat_mode_the_iso_value() {
        let tf = TransferFunction::from_flat(&[0.0, 0.0, 1.0, 1.0], &[0.0, 1.0, 1.0, 1.0]).unwrap();
        let mut scene = Scene {
            iso: Some(0.4),
            mode: RenderMode::Iso,
            ..Scene::default()
        };
        scene.set_transfer_function(tf.clone());
        scene.preset = Some("ct-bone".into());
        // Patches and the typed edits follow the same rules.
        let next = patched(&scene, json!({"preset": "mr-default"})).unwrap();
        assert_eq!(
            (next.preset.as_deref(), next.transfer_function.is_none()),
            (Some("mr-default"), true)
        );
        let mut edited = scene.clone();
        edited.set_preset("mr-default");
        assert_eq!(edited, next);
        let tf_json = serde_json::to_value(&tf).unwrap();
        let next = patched(&scene, json!({"transfer_function": tf_json})).unwrap();
        assert_eq!(
            (next.preset.is_none(), next.transfer_function.is_some()),
            (true, true)
        );
        // Setting both in one edit keeps both.
        let both = patched(
            &scene,
            json!({"preset": "mr-default", "transfer_function": tf_json}),
        )
        .unwrap();
        assert!(both.preset.is_some() && both.transfer_function.is_some());
        // Surface keeps the iso value, composite forgets it unless the edit sets it.
        for (mode, iso) in [("surface", Some(0.4)), ("composite", None), ("mip", None)] {
            let next = patched(&scene, json!({ "mode": mode })).unwrap();
            assert_eq!(next.iso, iso, "{mode}");
            let mut edited = scene.clone();
            edited.set_mode(next.mode);
            assert_eq!(edited.iso, iso, "{mode}");
        }
        let next = patched(&scene, json!({"mode": "composite", "iso": 0.7})).unwrap();
        assert_eq!(next.iso, Some(0.7));
        // A null preset clears only the preset.
        let next = patched(&scene, json!({"preset": null})).unwrap();
        assert!(next.preset.is_none() && next.transfer_function.is_some());
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

    #[test]
    fn a_steep_preset_brings_pre_integration() {
        use glint_volume::Sampling;
        let scene = Scene::default();
        assert_eq!(scene.sampling, Sampling::Point);
        let mut edited = scene.clone();
        edited.set_preset("ct-soft-tissue");
        assert_eq!(edited.sampling, Sampling::PreIntegrated);
        let next = patched(&scene, json!({"preset": "ct-soft-tissue"})).unwrap();
        assert_eq!(next, edited);
        // Back to a gentle preset: point sampling again.
        edited.set_preset("ct-bone");
        assert_eq!(edited.sampling, Sampling::Point);
        // Sampling set in the same edit wins.
        let both = patched(
            &scene,
            json!({"preset": "ct-soft-tissue", "sampling": "point"}),
        )
        .unwrap();
        assert_eq!(both.sampling, Sampling::Point);
    }
}
