//! Camera paths: a turntable's frames along camera keys read from a JSON file instead
//! of round the vertical axis (`glint render --camera-path keys.json --frames N`,
//! `glint.turntable(..., keys=[...])`).
//!
//! A key is a camera as the scene's `camera` serialises it (`view`, `azimuth`,
//! `elevation`, `zoom`, `projection`): `azimuth`, `elevation` and `zoom` are required,
//! `view` and `projection` may be given and must then be the same in every key (a path
//! cannot move between named views or projections); a field the camera does not have
//! is refused. The keys are evenly spaced in time, the first frame showing the first
//! key and the last frame the last one. Between two keys the eye moves over the
//! sphere round the scene's centre by its two spherical angles: azimuth and elevation
//! are each interpolated linearly in degrees, as written in the keys (so the keys'
//! winding is kept: azimuth 0 then 360 is one whole turn, not a standstill, which a
//! great-circle slerp of the eye's direction would make of it), and the zoom
//! geometrically (a constant rate of magnification: zoom 1 to 4 passes 2 half way).

use std::path::{Path, PathBuf};

use glint_core::{CameraSpec, Projection, View};
use serde::{Deserialize, Serialize};

/// The most keys a camera path may have.
pub const MAX_CAMERA_KEYS: usize = 10_000;

/// One key of a [`CameraPath`]: a camera state as the scene's `camera` serialises it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraKey {
    /// The named view (all keys alike); the scene's when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view: Option<View>,
    /// Degrees about the view's up axis.
    pub azimuth: f64,
    /// Degrees about the camera's right axis.
    pub elevation: f64,
    /// Magnification (0.001..=1000).
    pub zoom: f64,
    /// The projection (all keys alike); the scene's when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub projection: Option<Projection>,
}

/// Camera keys a turntable's frames follow (see the module's text for how they are
/// interpolated).
///
/// ```
/// use glint_render::{CameraPath, Scene};
///
/// let path = CameraPath::from_json(
///     r#"[{"azimuth": 0, "elevation": 0, "zoom": 1},
///         {"azimuth": 90, "elevation": 30, "zoom": 4}]"#,
/// )
/// .unwrap();
/// let middle = path.frame_camera(&Scene::default().camera, 1, 3);
/// assert_eq!((middle.azimuth, middle.elevation, middle.zoom), (45.0, 15.0, 2.0));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    keys: Vec<CameraKey>,
}

/// Why camera keys were refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CameraPathError {
    /// The file could not be read.
    #[error("cannot read the camera keys {}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The error.
        #[source]
        source: std::io::Error,
    },
    /// The JSON is not a list of camera keys (a missing or unknown field, a wrong
    /// type); `why` says where.
    #[error("camera keys{}: {why}", source_name(.path))]
    Json {
        /// The file, when read from one.
        path: Option<PathBuf>,
        /// serde's message, with the key's place (`[2].zoom: ...`).
        why: String,
    },
    /// Fewer than two keys, or more than [`MAX_CAMERA_KEYS`].
    #[error("camera keys{}: {count} keys: expected 2..={max}", source_name(.path), max = MAX_CAMERA_KEYS)]
    Count {
        /// The file, when read from one.
        path: Option<PathBuf>,
        /// The number of keys given.
        count: usize,
    },
    /// A key is out of range, or keys differ in view or projection.
    #[error("camera keys{}: key {index}: {why}", source_name(.path))]
    Key {
        /// The file, when read from one.
        path: Option<PathBuf>,
        /// The key (from 0).
        index: usize,
        /// What is wrong.
        why: String,
    },
}

fn source_name(path: &Option<PathBuf>) -> String {
    path.as_ref()
        .map(|p| format!(" in {}", p.display()))
        .unwrap_or_default()
}

impl CameraPath {
    /// The keys, checked: at least two, each camera valid ([`CameraSpec::validate`]:
    /// finite angles within ±3600°, zoom 0.001..=1000), one view and one projection.
    pub fn new(keys: Vec<CameraKey>) -> Result<CameraPath, CameraPathError> {
        if !(2..=MAX_CAMERA_KEYS).contains(&keys.len()) {
            return Err(CameraPathError::Count {
                path: None,
                count: keys.len(),
            });
        }
        let key_error = |index, why: String| CameraPathError::Key {
            path: None,
            index,
            why,
        };
        for (index, key) in keys.iter().enumerate() {
            let spec = CameraSpec {
                azimuth: key.azimuth,
                elevation: key.elevation,
                zoom: key.zoom,
                ..CameraSpec::default()
            };
            spec.validate()
                .map_err(|e| key_error(index, e.to_string()))?;
            if key.view != keys[0].view {
                return Err(key_error(
                    index,
                    "its view differs from the first key's (a path keeps one view)".into(),
                ));
            }
            if key.projection != keys[0].projection {
                return Err(key_error(
                    index,
                    "its projection differs from the first key's (a path keeps one projection)"
                        .into(),
                ));
            }
        }
        Ok(CameraPath { keys })
    }

    /// Keys from JSON text: a list of camera objects.
    pub fn from_json(text: &str) -> Result<CameraPath, CameraPathError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let keys: Vec<CameraKey> =
            serde_path_to_error::deserialize(de).map_err(|e| CameraPathError::Json {
                path: None,
                why: json_why(&e),
            })?;
        CameraPath::new(keys)
    }

    /// Keys from a JSON file ([`CameraPath::from_json`]); errors name the file.
    pub fn load(path: &Path) -> Result<CameraPath, CameraPathError> {
        let text = std::fs::read_to_string(path).map_err(|source| CameraPathError::Read {
            path: path.into(),
            source,
        })?;
        CameraPath::from_json(&text).map_err(|e| e.in_file(path))
    }

    /// The keys.
    pub fn keys(&self) -> &[CameraKey] {
        &self.keys
    }

    /// The camera of frame `k` of `frames` (at least 2): `base` (the scene's camera)
    /// with the interpolated azimuth, elevation and zoom, and the keys' view and
    /// projection where they give them. Frame 0 is the first key, frame `frames - 1`
    /// the last.
    pub fn frame_camera(&self, base: &CameraSpec, k: u32, frames: u32) -> CameraSpec {
        let last = (self.keys.len() - 1) as f64;
        let u = if frames > 1 {
            f64::from(k.min(frames - 1)) * last / f64::from(frames - 1)
        } else {
            0.0
        };
        let i = (u.floor() as usize).min(self.keys.len() - 2);
        let t = u - i as f64;
        let (a, b) = (&self.keys[i], &self.keys[i + 1]);
        let lerp = |x: f64, y: f64| if t == 0.0 { x } else { x + (y - x) * t };
        // Geometric: a.zoom (b.zoom / a.zoom)^t (exact where the ratio's root is).
        let zoom = if t == 0.0 {
            a.zoom
        } else {
            a.zoom * (b.zoom / a.zoom).powf(t)
        };
        CameraSpec {
            view: a.view.unwrap_or(base.view),
            azimuth: lerp(a.azimuth, b.azimuth),
            elevation: lerp(a.elevation, b.elevation),
            zoom,
            projection: a.projection.unwrap_or(base.projection),
            ..*base
        }
    }
}

impl CameraPathError {
    /// The same error naming the file it came from.
    fn in_file(self, file: &Path) -> CameraPathError {
        let p = Some(file.to_path_buf());
        match self {
            CameraPathError::Json { why, .. } => CameraPathError::Json { path: p, why },
            CameraPathError::Count { count, .. } => CameraPathError::Count { path: p, count },
            CameraPathError::Key { index, why, .. } => CameraPathError::Key {
                path: p,
                index,
                why,
            },
            other => other,
        }
    }
}

/// serde's message with the place it failed (`[1]: missing field `zoom``): one line.
fn json_why(e: &serde_path_to_error::Error<serde_json::Error>) -> String {
    let place = e.path().to_string();
    let inner = e.inner().to_string();
    if place == "." || place.is_empty() {
        inner
    } else {
        format!("{place}: {inner}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        CameraPath::from_json(text).unwrap_err().to_string()
    }

    #[test]
    fn bad_keys_are_refused_in_one_line_each() {
        let missing =
            err(r#"[{"azimuth": 0, "elevation": 0, "zoom": 1}, {"azimuth": 9, "elevation": 0}]"#);
        assert!(
            missing.contains("[1]") && missing.contains("missing field `zoom`"),
            "{missing}"
        );
        let unknown = err(r#"[{"azimuth": 0, "elevation": 0, "zoom": 1, "target": [0, 0, 0]}]"#);
        assert!(unknown.contains("unknown field `target`"), "{unknown}");
        let one = err(r#"[{"azimuth": 0, "elevation": 0, "zoom": 1}]"#);
        assert!(one.contains("1 keys: expected 2.."), "{one}");
        let zoom = err(
            r#"[{"azimuth": 0, "elevation": 0, "zoom": 1}, {"azimuth": 0, "elevation": 0, "zoom": 0}]"#,
        );
        assert!(zoom.contains("key 1") && zoom.contains("zoom"), "{zoom}");
        let views = err(
            r#"[{"azimuth": 0, "elevation": 0, "zoom": 1, "view": "left"}, {"azimuth": 0, "elevation": 0, "zoom": 1}]"#,
        );
        assert!(views.contains("key 1") && views.contains("view"), "{views}");
        assert!(err("{}").contains("expected a sequence"), "{}", err("{}"));
        for e in [missing, unknown, one, zoom, views] {
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn frames_run_from_the_first_key_to_the_last_keeping_the_winding() {
        let path = CameraPath::from_json(
            r#"[{"azimuth": 0, "elevation": 0, "zoom": 1},
                {"azimuth": 180, "elevation": 40, "zoom": 2},
                {"azimuth": 360, "elevation": 0, "zoom": 8, "view": null}]"#,
        )
        .unwrap();
        let mut base = CameraSpec {
            view: View::Left,
            ..CameraSpec::default()
        };
        base.projection = Projection::Orthographic;
        let cams: Vec<CameraSpec> = (0..5).map(|k| path.frame_camera(&base, k, 5)).collect();
        let az: Vec<f64> = cams.iter().map(|c| c.azimuth).collect();
        assert_eq!(az, [0.0, 90.0, 180.0, 270.0, 360.0]);
        let el: Vec<f64> = cams.iter().map(|c| c.elevation).collect();
        assert_eq!(el, [0.0, 20.0, 40.0, 20.0, 0.0]);
        // Geometric zoom: half way from 1 to 2 is sqrt 2, from 2 to 8 is 4.
        assert!((cams[1].zoom - 2f64.sqrt()).abs() < 1e-12);
        assert!((cams[3].zoom - 4.0).abs() < 1e-12);
        assert_eq!(cams[4].zoom, 8.0);
        // The scene's view and projection where the keys give none.
        assert!(cams
            .iter()
            .all(|c| c.view == View::Left && c.projection == Projection::Orthographic));
    }
}
