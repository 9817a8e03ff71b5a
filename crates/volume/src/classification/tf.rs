//! Transfer functions (scalar value -> colour and opacity) and materials.

use std::path::Path;

use serde::{Deserialize, Serialize};

use glint_core::lighting::MaterialOverrides;
use glint_core::RenderError;

/// A 1D transfer function: piecewise-linear opacity and colour over the scalar value,
/// constant beyond the first and last points (VTK's piecewise and colour transfer
/// functions with clamping on). In JSON: `{"opacity": [[value, a], ...], "color":
/// [[value, r, g, b], ...]}`, validated when read.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "TfPoints", into = "TfPoints")]
pub struct TransferFunction {
    /// `(value, opacity)` points, values strictly increasing, opacity in [0, 1]:
    /// opacity per unit distance of one voxel (the smallest spacing).
    pub opacity: Vec<(f64, f64)>,
    /// `(value, [r, g, b])` points, values strictly increasing, sRGB components in
    /// [0, 1].
    pub color: Vec<(f64, [f64; 3])>,
}

fn piecewise<const N: usize>(points: &[(f64, [f64; N])], x: f64) -> [f64; N] {
    let first = points[0];
    if x <= first.0 {
        return first.1;
    }
    for w in points.windows(2) {
        let (x0, y0) = w[0];
        let (x1, y1) = w[1];
        if x <= x1 {
            let t = (x - x0) / (x1 - x0);
            let mut out = [0.0; N];
            for c in 0..N {
                out[c] = y0[c] + t * (y1[c] - y0[c]);
            }
            return out;
        }
    }
    points[points.len() - 1].1
}

impl TransferFunction {
    /// Builds and validates a transfer function.
    pub fn new(opacity: Vec<(f64, f64)>, color: Vec<(f64, [f64; 3])>) -> Result<Self, RenderError> {
        let tf = TransferFunction { opacity, color };
        tf.validate()?;
        Ok(tf)
    }

    /// Builds from VTK/Slicer flat arrays: opacity `x0 a0 x1 a1 ...`, colour
    /// `x0 r0 g0 b0 ...` (the count prefix Slicer writes is not included).
    pub fn from_flat(opacity: &[f64], color: &[f64]) -> Result<Self, RenderError> {
        if !opacity.len().is_multiple_of(2) || !color.len().is_multiple_of(4) {
            return Err(RenderError::TransferFunction(
                "flat arrays need pairs (value, opacity) and quads (value, r, g, b)".into(),
            ));
        }
        TransferFunction::new(
            opacity.chunks(2).map(|c| (c[0], c[1])).collect(),
            color
                .chunks(4)
                .map(|c| (c[0], [c[1], c[2], c[3]]))
                .collect(),
        )
    }

    /// Checks: at least one point each, finite, strictly increasing values, opacity and
    /// colour in [0, 1].
    pub fn validate(&self) -> Result<(), RenderError> {
        let bad = |what: String| Err(RenderError::TransferFunction(what));
        if self.opacity.is_empty() || self.color.is_empty() {
            return bad("needs at least one opacity point and one colour point".into());
        }
        let check_x = |xs: &mut dyn Iterator<Item = f64>, what: &str| {
            let mut prev = f64::NEG_INFINITY;
            for x in xs {
                if !x.is_finite() || x <= prev {
                    return Err(RenderError::TransferFunction(format!(
                        "{what} point values must be finite and strictly increasing (at {x})"
                    )));
                }
                prev = x;
            }
            Ok(())
        };
        check_x(&mut self.opacity.iter().map(|p| p.0), "opacity")?;
        check_x(&mut self.color.iter().map(|p| p.0), "colour")?;
        for &(x, a) in &self.opacity {
            if !(0.0..=1.0).contains(&a) {
                return bad(format!("opacity {a} at value {x} is outside [0, 1]"));
            }
        }
        for &(x, c) in &self.color {
            if c.iter().any(|v| !(0.0..=1.0).contains(v)) {
                return bad(format!("colour {c:?} at value {x} is outside [0, 1]"));
            }
        }
        Ok(())
    }

    /// Opacity per voxel of distance at `x`.
    pub fn opacity_at(&self, x: f64) -> f64 {
        let pts: Vec<(f64, [f64; 1])> = self.opacity.iter().map(|&(x, a)| (x, [a])).collect();
        piecewise(&pts, x)[0]
    }

    /// sRGB colour at `x`.
    pub fn color_at(&self, x: f64) -> [f64; 3] {
        piecewise(&self.color, x)
    }

    /// The value range its points span (union of opacity and colour points).
    pub fn domain(&self) -> (f64, f64) {
        let xs = self
            .opacity
            .iter()
            .map(|p| p.0)
            .chain(self.color.iter().map(|p| p.0));
        xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        })
    }

    /// The same function with every point value mapped by `x -> x * scale + offset`.
    pub fn remapped(&self, scale: f64, offset: f64) -> TransferFunction {
        TransferFunction {
            opacity: self
                .opacity
                .iter()
                .map(|&(x, a)| (x * scale + offset, a))
                .collect(),
            color: self
                .color
                .iter()
                .map(|&(x, c)| (x * scale + offset, c))
                .collect(),
        }
    }

    /// The function's own window: `level` the middle and `window` the width of its
    /// opacity ramp, from the last point at the lowest opacity before the first point
    /// at the highest opacity to that point (for a falling ramp, the other way round).
    /// A grey MIP ramp from `lo` to `hi` has the window `hi - lo` at level
    /// `(lo + hi) / 2`, a radiology viewer's window exactly; a Slicer CT preset's is
    /// the rise of its opacity (ct-bone: -16.4 to 641.4 HU). A function of constant
    /// opacity has the span of its points as its window (1 when that span is empty).
    pub fn window_level(&self) -> WindowLevel {
        let ops = &self.opacity;
        let max = ops.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
        let min = ops.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let (lo, hi) = self.domain();
        let whole = WindowLevel {
            window: if hi > lo { hi - lo } else { 1.0 },
            level: (lo + hi) / 2.0,
        };
        if max <= min {
            return whole;
        }
        let top = ops
            .iter()
            .position(|p| p.1 == max)
            .expect("a point has the maximum");
        // The foot of the ramp: before the top if the ramp rises, else after it.
        let foot = if top > 0 {
            let low = ops[..top].iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            ops[..top]
                .iter()
                .rposition(|p| p.1 == low)
                .map(|i| ops[i].0)
        } else {
            let low = ops[1..].iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
            ops.iter().position(|p| p.1 == low).map(|i| ops[i].0)
        };
        match foot {
            Some(x) if x != ops[top].0 => WindowLevel {
                window: (ops[top].0 - x).abs(),
                level: (ops[top].0 + x) / 2.0,
            },
            _ => whole,
        }
    }

    /// The function remapped linearly along the value axis so that its own window
    /// ([`TransferFunction::window_level`]) becomes `target`: a value `v` reads what
    /// the function had at `own.level + (v - target.level) * own.window /
    /// target.window`, so the value at `target.level` reads the function's centre.
    pub fn with_window_level(&self, target: WindowLevel) -> Result<TransferFunction, RenderError> {
        target.validate()?;
        let own = self.window_level();
        let scale = target.window / own.window;
        let tf = self.remapped(scale, target.level - own.level * scale);
        tf.validate()?;
        Ok(tf)
    }

    /// Reads the JSON form: `{"opacity": [[value, a], ...], "color": [[value, r, g, b],
    /// ...]}` plus optional material fields `ambient`, `diffuse`, `specular`, `shade`
    /// and the specular `power` (the lobe's n).
    pub fn from_json_file(path: &Path) -> Result<TransferFunctionFile, RenderError> {
        let file_err = |what: String| RenderError::TransferFunctionFile {
            path: path.to_path_buf(),
            what,
        };
        let meta = std::fs::metadata(path).map_err(|e| file_err(e.to_string()))?;
        // A transfer function is a few hundred bytes; refuse anything absurd before
        // reading it.
        if meta.len() > 1 << 20 {
            return Err(file_err(format!(
                "{} bytes is too large for a transfer function (limit 1 MiB)",
                meta.len()
            )));
        }
        let text = std::fs::read_to_string(path).map_err(|e| file_err(e.to_string()))?;
        Self::from_json_str(&text).map_err(|e| match e {
            RenderError::TransferFunction(what) => file_err(what),
            other => file_err(other.to_string()),
        })
    }

    /// Parses the JSON form described in [`TransferFunction::from_json_file`].
    pub fn from_json_str(text: &str) -> Result<TransferFunctionFile, RenderError> {
        let doc: TfJson = serde_json::from_str(text)
            .map_err(|e| RenderError::TransferFunction(format!("bad JSON: {e}")))?;
        let opacity = doc.opacity.iter().map(|p| (p[0], p[1])).collect();
        let color = doc
            .color
            .iter()
            .map(|p| (p[0], [p[1], p[2], p[3]]))
            .collect();
        let tf = TransferFunction::new(opacity, color)?;
        Ok(TransferFunctionFile {
            tf,
            material: MaterialOverrides {
                ambient: doc.ambient,
                diffuse: doc.diffuse,
                specular: doc.specular,
                shade: doc.shade,
            },
            power: doc.power,
            notes: Vec::new(),
        })
    }
}

/// A window (width) and level (centre) on the value axis, in the volume's units (HU
/// for CT), as radiology viewers set them. In JSON: `{"window": 400, "level": 40}`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindowLevel {
    /// The width: positive and finite.
    pub window: f64,
    /// The centre: finite.
    pub level: f64,
}

impl WindowLevel {
    /// Checks the width is positive and both are finite.
    pub fn validate(&self) -> Result<(), RenderError> {
        if !(self.window.is_finite() && self.window > 0.0) {
            return Err(RenderError::Parameter(format!(
                "window {}: expected a positive width",
                self.window
            )));
        }
        if !self.level.is_finite() {
            return Err(RenderError::Parameter(format!(
                "level {}: expected a finite value",
                self.level
            )));
        }
        Ok(())
    }
}

/// What a transfer-function JSON file holds.
#[derive(Clone, Debug, PartialEq)]
pub struct TransferFunctionFile {
    /// The function.
    pub tf: TransferFunction,
    /// The material fields it sets.
    pub material: MaterialOverrides,
    /// The specular power it sets (the lobe's n).
    pub power: Option<f64>,
    /// What the file held that glint does not use (e.g. a Slicer gradient opacity),
    /// one line each, for the user.
    pub notes: Vec<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TfJson {
    opacity: Vec<[f64; 2]>,
    color: Vec<[f64; 4]>,
    ambient: Option<f32>,
    diffuse: Option<f32>,
    specular: Option<f32>,
    power: Option<f64>,
    shade: Option<bool>,
}

/// The JSON form of a [`TransferFunction`].
#[derive(Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TfPoints {
    opacity: Vec<[f64; 2]>,
    color: Vec<[f64; 4]>,
}

impl TryFrom<TfPoints> for TransferFunction {
    type Error = RenderError;
    fn try_from(p: TfPoints) -> Result<Self, RenderError> {
        TransferFunction::new(
            p.opacity.iter().map(|q| (q[0], q[1])).collect(),
            p.color.iter().map(|q| (q[0], [q[1], q[2], q[3]])).collect(),
        )
    }
}

impl From<TransferFunction> for TfPoints {
    fn from(tf: TransferFunction) -> Self {
        TfPoints {
            opacity: tf.opacity.iter().map(|&(x, a)| [x, a]).collect(),
            color: tf
                .color
                .iter()
                .map(|&(x, c)| [x, c[0], c[1], c[2]])
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> TransferFunction {
        TransferFunction::from_flat(
            &[0.0, 0.0, 10.0, 1.0],
            &[0.0, 0.0, 0.0, 0.0, 10.0, 1.0, 0.5, 0.0],
        )
        .unwrap()
    }

    #[test]
    fn piecewise_linear_and_clamped() {
        let tf = ramp();
        assert_eq!(tf.opacity_at(-5.0), 0.0);
        assert!((tf.opacity_at(2.5) - 0.25).abs() < 1e-12);
        assert_eq!(tf.opacity_at(50.0), 1.0);
        assert_eq!(tf.color_at(5.0), [0.5, 0.25, 0.0]);
    }

    #[test]
    fn window_level_remaps_the_value_axis_linearly() {
        // A ramp from 0 to 10: its window is 10 wide at level 5.
        let tf = ramp();
        assert_eq!(
            tf.window_level(),
            WindowLevel {
                window: 10.0,
                level: 5.0
            }
        );
        let wl = tf
            .with_window_level(WindowLevel {
                window: 4.0,
                level: 100.0,
            })
            .unwrap();
        // The value at the level reads the function's centre; the window's ends its
        // foot and top; a quarter of the way up, a quarter of the opacity.
        assert!((wl.opacity_at(100.0) - 0.5).abs() < 1e-12);
        assert_eq!(wl.opacity_at(98.0), 0.0);
        assert_eq!(wl.opacity_at(102.0), 1.0);
        assert!((wl.opacity_at(99.0) - 0.25).abs() < 1e-12);
        assert_eq!(wl.color_at(100.0), tf.color_at(5.0));
        assert_eq!(
            wl.window_level(),
            WindowLevel {
                window: 4.0,
                level: 100.0
            }
        );
        // Slicer's ct-bone: the rise from -16.4458 to 641.385 HU.
        let bone = crate::preset("ct-bone")
            .unwrap()
            .transfer_function(0.0)
            .unwrap();
        let own = bone.window_level();
        assert!((own.window - 657.8308).abs() < 1e-9, "{own:?}");
        assert!((own.level - 312.4696).abs() < 1e-9, "{own:?}");
        // A falling ramp measures from its top to its foot.
        let fall =
            TransferFunction::from_flat(&[2.0, 1.0, 6.0, 0.0], &[0.0, 1.0, 1.0, 1.0]).unwrap();
        assert_eq!(
            fall.window_level(),
            WindowLevel {
                window: 4.0,
                level: 4.0
            }
        );
        for bad in [
            (0.0, 1.0),
            (-3.0, 1.0),
            (f64::NAN, 0.0),
            (1.0, f64::INFINITY),
        ] {
            let target = WindowLevel {
                window: bad.0,
                level: bad.1,
            };
            assert!(tf.with_window_level(target).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn bad_functions_are_rejected() {
        assert!(TransferFunction::from_flat(&[1.0, 0.0, 0.0, 1.0], &[0.0, 1.0, 1.0, 1.0]).is_err());
        assert!(TransferFunction::from_flat(&[0.0, 1.5], &[0.0, 1.0, 1.0, 1.0]).is_err());
        assert!(TransferFunction::from_flat(&[0.0, f64::NAN], &[0.0, 1.0, 1.0, 1.0]).is_err());
        assert!(TransferFunction::from_json_str("{\"opacity\": [[0, 0]]}").is_err());
        assert!(TransferFunction::from_json_str("not json").is_err());
        let file = TransferFunction::from_json_str(
            r#"{"opacity": [[0, 0], [1, 1]], "color": [[0, 1, 0, 0]], "specular": 0.5, "power": 7}"#,
        )
        .unwrap();
        assert_eq!(file.tf.opacity.len(), 2);
        assert_eq!(file.material.specular, Some(0.5));
        assert_eq!(file.power, Some(7.0));
    }

    #[test]
    fn serde_form_is_validated() {
        let tf: TransferFunction =
            serde_json::from_str(r#"{"opacity": [[0, 0], [1, 1]], "color": [[0, 1, 0, 0]]}"#)
                .unwrap();
        let back = serde_json::to_string(&tf).unwrap();
        assert_eq!(serde_json::from_str::<TransferFunction>(&back).unwrap(), tf);
        // Unsorted points and opacities above 1 are refused when read.
        for bad in [
            r#"{"opacity": [[1, 0], [0, 1]], "color": [[0, 1, 0, 0]]}"#,
            r#"{"opacity": [[0, 2]], "color": [[0, 1, 0, 0]]}"#,
            r#"{"opacity": [[0, 1]], "color": [[0, 1, 0, 0]], "x": 1}"#,
        ] {
            assert!(
                serde_json::from_str::<TransferFunction>(bad).is_err(),
                "{bad}"
            );
        }
    }
}
