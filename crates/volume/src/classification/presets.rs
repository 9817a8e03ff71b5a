//! Transfer-function presets named after 3D Slicer's volume rendering presets.
//!
//! Source of every number below (transfer-function points and the material's ambient,
//! diffuse, specular and specular power): 3D Slicer,
//! `Modules/Loadable/VolumeRendering/Resources/presets.xml` (Slicer/Slicer on GitHub,
//! commit 1a889b0d8dc3b034ac11631a237a54ada115ef7e), the `scalarOpacity`,
//! `colorTransfer`, `ambient`, `diffuse`, `specular`, `specularPower` and `shade`
//! attributes of each `VolumeProperty`, with Slicer's leading point count dropped.
//! Slicer's `gradientOpacity` is the constant 1 in every preset, so it is not stored.
//!
//! CT presets are in Hounsfield units and used as they are. MR intensities have no
//! absolute scale (Slicer leaves the user to shift its MR presets by hand), so MR
//! presets are *relative*: their values are scaled so the preset's last point lands on
//! the volume's maximum.

use super::preint::Sampling;
use super::tf::TransferFunction;
use glint_core::Material;
use glint_core::RenderError;

/// One named preset.
#[derive(Clone, Copy, Debug)]
pub struct Preset {
    /// The name users type (Slicer's name in lower case).
    pub name: &'static str,
    /// Flat `value opacity` pairs.
    pub opacity: &'static [f64],
    /// Flat `value r g b` quads.
    pub color: &'static [f64],
    /// ambient, diffuse, specular, specular power.
    pub material: [f32; 4],
    /// Slicer's `shade` flag.
    pub shade: bool,
    /// Whether values are relative to the volume's maximum (MR presets).
    pub relative: bool,
}

impl Preset {
    /// The transfer function, scaled to a volume whose values reach `volume_max` when
    /// the preset is relative.
    pub fn transfer_function(&self, volume_max: f64) -> Result<TransferFunction, RenderError> {
        let tf = TransferFunction::from_flat(self.opacity, self.color)?;
        if self.relative {
            let (_, top) = tf.domain();
            if top > 0.0 && volume_max.is_finite() && volume_max > 0.0 {
                return Ok(tf.remapped(volume_max / top, 0.0));
            }
        }
        Ok(tf)
    }

    /// The material.
    pub fn material(&self) -> Material {
        let [ambient, diffuse, specular, _] = self.material;
        Material {
            ambient,
            diffuse,
            specular,
            shade: self.shade,
        }
    }

    /// The specular power (Slicer's `specularPower`): the default shininess n.
    pub fn specular_power(&self) -> f64 {
        self.material[3] as f64
    }

    /// Whether the preset's opacity is steep: somewhere it changes by 1 over less than
    /// [`STEEP_FRACTION`] of the function's domain (under 29 HU for Slicer's CT
    /// presets, whose domain is -2048..3661: `ct-soft-tissue` goes from 0 to 1 over
    /// 7 HU). A step of half a voxel crosses such a ramp at a skin or vessel edge
    /// between two samples, and where the crossing falls varies slowly over the image:
    /// moiré (issue 42, item 6d). Such presets are pre-integrated by default
    /// ([`Preset::sampling`]).
    pub fn is_steep(&self) -> bool {
        let points: Vec<(f64, f64)> = self.opacity.chunks(2).map(|p| (p[0], p[1])).collect();
        let span = match (points.first(), points.last()) {
            (Some(a), Some(b)) if b.0 > a.0 => b.0 - a.0,
            _ => return false,
        };
        (points.windows(2)).any(|w| {
            let (dv, da) = (w[1].0 - w[0].0, (w[1].1 - w[0].1).abs());
            da > 0.0 && da * span * STEEP_FRACTION > dv
        })
    }

    /// The sampling a scene takes when it chooses this preset: pre-integrated for a
    /// steep preset ([`Preset::is_steep`]), else point sampling.
    pub fn sampling(&self) -> Sampling {
        if self.is_steep() {
            Sampling::PreIntegrated
        } else {
            Sampling::Point
        }
    }
}

/// The fraction of a preset's domain under which an opacity change of 1 is steep
/// ([`Preset::is_steep`]).
pub const STEEP_FRACTION: f64 = 1.0 / 200.0;

macro_rules! preset {
    ($name:literal, [$($o:expr),*], [$($c:expr),*], [$a:expr, $d:expr, $s:expr, $p:expr], $shade:expr, $rel:expr) => {
        Preset {
            name: $name,
            opacity: &[$($o as f64),*],
            color: &[$($c as f64),*],
            material: [$a, $d, $s, $p],
            shade: $shade,
            relative: $rel,
        }
    };
}

/// Every preset. `phantom` is glint's own, for the built-in Shepp-Logan head (values
/// 0..1); the rest are Slicer's.
pub const PRESETS: &[Preset] = &[
    // glint's own: skull as faint glass, the phantom's denser inner ellipsoids (0.3)
    // opaque and warm, brain matter (0.2) a faint haze.
    preset!(
        "phantom",
        [
            0.0, 0.0, 0.19, 0.0, 0.21, 0.003, 0.25, 0.003, 0.28, 0.3, 0.34, 0.3, 0.4, 0.0, 0.55,
            0.0, 0.75, 0.05, 1.0, 0.05
        ],
        [
            0.0, 0.0, 0.0, 0.0, 0.2, 0.55, 0.6, 0.75, 0.3, 1.0, 0.62, 0.25, 0.45, 1.0, 0.62, 0.25,
            0.75, 0.95, 0.95, 0.9, 1.0, 0.95, 0.95, 0.9
        ],
        [0.15, 0.8, 0.6, 40.0],
        true,
        false
    ),
    // glint's own, for the `head` phantom (values 0..0.85): scalp a faint haze, the
    // skull glassy ivory, cerebrospinal fluid clear, the brain's surface opaque and
    // pink with a strong highlight; ventricles hidden inside it.
    preset!(
        "head",
        [
            0.0, 0.0, 0.04, 0.0, 0.08, 0.006, 0.14, 0.006, 0.2, 0.08, 0.3, 0.08, 0.33, 0.0, 0.42,
            0.0, 0.52, 0.8, 1.0, 0.8
        ],
        [
            0.0, 0.8, 0.62, 0.52, 0.14, 0.8, 0.62, 0.52, 0.2, 0.95, 0.92, 0.84, 0.3, 0.95, 0.92,
            0.84, 0.42, 0.93, 0.6, 0.56, 1.0, 0.93, 0.6, 0.56
        ],
        [0.12, 0.75, 0.5, 30.0],
        true,
        false
    ),
    preset!(
        "ct-aaa",
        [
            -3024, 0, 143.556, 0, 166.222, 0.686275, 214.389, 0.696078, 419.736, 0.833333, 3071,
            0.803922
        ],
        [
            -3024, 0, 0, 0, 143.556, 0.615686, 0.356863, 0.184314, 166.222, 0.882353, 0.603922,
            0.290196, 214.389, 1, 1, 1, 419.736, 1, 0.937033, 0.954531, 3071, 0.827451, 0.658824,
            1
        ],
        [0.1, 0.9, 0.2, 10.0],
        true,
        false
    ),
    preset!(
        "ct-aaa2",
        [
            -3024, 0, 129.542, 0, 145.244, 0.166667, 157.02, 0.5, 169.918, 0.627451, 395.575,
            0.8125, 1578.73, 0.8125, 3071, 0.8125
        ],
        [
            -3024, 0, 0, 0, 129.542, 0.54902, 0.25098, 0.14902, 145.244, 0.6, 0.627451, 0.843137,
            157.02, 0.890196, 0.47451, 0.6, 169.918, 0.992157, 0.870588, 0.392157, 395.575, 1,
            0.886275, 0.658824, 1578.73, 1, 0.829256, 0.957922, 3071, 0.827451, 0.658824, 1
        ],
        [0.1, 0.9, 0.2, 10.0],
        true,
        false
    ),
    preset!(
        "ct-bone",
        [-3024, 0, -16.4458, 0, 641.385, 0.715686, 3071, 0.705882],
        [
            -3024, 0, 0, 0, -16.4458, 0.729412, 0.254902, 0.301961, 641.385, 0.905882, 0.815686,
            0.552941, 3071, 1, 1, 1
        ],
        [0.1, 0.9, 0.2, 10.0],
        true,
        false
    ),
    preset!(
        "ct-bones",
        [-1000, 0, 152.19, 0, 278.93, 0.190476, 952, 0.2],
        [
            -1000, 0.3, 0.3, 1, -488, 0.3, 1, 0.3, 463.28, 1, 0, 0, 659.15, 1, 0.912535, 0.0374849,
            953, 1, 0.3, 0.3
        ],
        [0.2, 1.0, 0.0, 1.0],
        true,
        false
    ),
    preset!(
        "ct-cardiac",
        [
            -3024, 0, -77.6875, 0, 94.9518, 0.285714, 179.052, 0.553571, 260.439, 0.848214, 3071,
            0.875
        ],
        [
            -3024, 0, 0, 0, -77.6875, 0.54902, 0.25098, 0.14902, 94.9518, 0.882353, 0.603922,
            0.290196, 179.052, 1, 0.937033, 0.954531, 260.439, 0.615686, 0, 0, 3071, 0.827451,
            0.658824, 1
        ],
        [0.1, 0.9, 0.2, 10.0],
        true,
        false
    ),
    preset!(
        "ct-cardiac2",
        [
            -3024, 0, 42.8964, 0, 163.488, 0.428571, 277.642, 0.776786, 1587, 0.754902, 3071,
            0.754902
        ],
        [
            -3024, 0, 0, 0, 42.8964, 0.54902, 0.25098, 0.14902, 163.488, 0.917647, 0.639216,
            0.0588235, 277.642, 1, 0.878431, 0.623529, 1587, 1, 1, 1, 3071, 0.827451, 0.658824, 1
        ],
        [0.1, 0.9, 0.2, 10.0],
        true,
        false
    ),
    preset!(
        "ct-cardiac3",
        [
            -3024, 0, -86.9767, 0, 45.3791, 0.169643, 139.919, 0.589286, 347.907, 0.607143,
            1224.16, 0.607143, 3071, 0.616071
        ],
        [
            -3024, 0, 0, 0, -86.9767, 0, 0.25098, 1, 45.3791, 1, 0, 0, 139.919, 1, 0.894893,
            0.894893, 347.907, 1, 1, 0.25098, 1224.16, 1, 1, 1, 3071, 0.827451, 0.658824, 1
        ],
        [0.1, 0.9, 0.2, 10.0],
        true,
        false
    ),
    preset!(
        "ct-chest-contrast-enhanced",
        [-3024, 0, 67.0106, 0, 251.105, 0.446429, 439.291, 0.625, 3071, 0.616071],
        [
            -3024, 0, 0, 0, 67.0106, 0.54902, 0.25098, 0.14902, 251.105, 0.882353, 0.603922,
            0.290196, 439.291, 1, 0.937033, 0.954531, 3071, 0.827451, 0.658824, 1
        ],
        [0.1, 0.9, 0.2, 10.0],
        true,
        false
    ),
    preset!(
        "ct-chest-vessels",
        [-3024, 0, -1278.35, 0, 22.8277, 0.428571, 439.291, 0.625, 3071, 0.616071],
        [
            -3024, 0, 0, 0, -1278.35, 0.54902, 0.25098, 0.14902, 22.8277, 0.882353, 0.603922,
            0.290196, 439.291, 1, 0.937033, 0.954531, 3071, 0.827451, 0.658824, 1
        ],
        [0.2, 1.0, 0.0, 1.0],
        true,
        false
    ),
    preset!(
        "ct-coronary-arteries",
        [-2048, 0, 136.47, 0, 159.215, 0.258929, 318.43, 0.571429, 478.693, 0.776786, 3661, 1],
        [
            -2048, 0, 0, 0, 136.47, 0, 0, 0, 159.215, 0.159804, 0.159804, 0.159804, 318.43,
            0.764706, 0.764706, 0.764706, 478.693, 1, 1, 1, 3661, 1, 1, 1
        ],
        [0.2, 1.0, 0.0, 1.0],
        false,
        false
    ),
    preset!(
        "ct-coronary-arteries-2",
        [
            -2048, 0, 142.677, 0, 145.016, 0.116071, 192.174, 0.5625, 217.24, 0.776786, 384.347,
            0.830357, 3661, 0.830357
        ],
        [
            -2048, 0, 0, 0, 142.677, 0, 0, 0, 145.016, 0.615686, 0, 0.0156863, 192.174, 0.909804,
            0.454902, 0, 217.24, 0.972549, 0.807843, 0.611765, 384.347, 0.909804, 0.909804, 1,
            3661, 1, 1, 1
        ],
        [0.2, 1.0, 0.0, 1.0],
        true,
        false
    ),
    preset!(
        "ct-coronary-arteries-3",
        [
            -2048, 0, 128.643, 0, 129.982, 0.0982143, 173.636, 0.669643, 255.884, 0.857143,
            584.878, 0.866071, 3661, 1
        ],
        [
            -2048, 0, 0, 0, 128.643, 0, 0, 0, 129.982, 0.615686, 0, 0.0156863, 173.636, 0.909804,
            0.454902, 0, 255.884, 0.886275, 0.886275, 0.886275, 584.878, 0.968627, 0.968627,
            0.968627, 3661, 1, 1, 1
        ],
        [0.1, 0.9, 0.2, 10.0],
        true,
        false
    ),
    preset!(
        "ct-cropped-volume-bone",
        [-2048, 0, -451, 0, -450, 1, 1050, 1, 3661, 1],
        [
            -2048, 0, 0, 0, -451, 0, 0, 0, -450, 0.0556356, 0.0556356, 0.0556356, 1050, 1, 1, 1,
            3661, 1, 1, 1
        ],
        [0.2, 1.0, 0.0, 1.0],
        false,
        false
    ),
    preset!(
        "ct-fat",
        [-1000, 0, -100, 0, -99, 0.15, -60, 0.15, -59, 0, 101.2, 0, 952, 0],
        [
            -1000, 0.3, 0.3, 1, -497.5, 0.3, 1, 0.3, -99, 0, 0, 1, -76.946, 0, 1, 0, -65.481,
            0.835431, 0.888889, 0.0165387, 83.89, 1, 0, 0, 463.28, 1, 0, 0, 659.15, 1, 0.912535,
            0.0374849, 2952, 1, 0.300267, 0.299886
        ],
        [0.2, 1.0, 0.0, 1.0],
        false,
        false
    ),
    preset!(
        "ct-liver-vasculature",
        [
            -2048, 0, 149.113, 0, 157.884, 0.482143, 339.96, 0.660714, 388.526, 0.830357, 1197.95,
            0.839286, 3661, 0.848214
        ],
        [
            -2048, 0, 0, 0, 149.113, 0, 0, 0, 157.884, 0.501961, 0.25098, 0, 339.96, 0.695386,
            0.59603, 0.36886, 388.526, 0.854902, 0.85098, 0.827451, 1197.95, 1, 1, 1, 3661, 1, 1,
            1
        ],
        [0.2, 1.0, 0.0, 1.0],
        false,
        false
    ),
    preset!(
        "ct-lung",
        [-1000, 0, -600, 0, -599, 0.15, -400, 0.15, -399, 0, 2952, 0],
        [
            -1000, 0.3, 0.3, 1, -600, 0, 0, 1, -530, 0.134704, 0.781726, 0.0724558, -460, 0.929244,
            1, 0.109473, -400, 0.888889, 0.254949, 0.0240258, 2952, 1, 0.3, 0.3
        ],
        [0.2, 1.0, 0.0, 1.0],
        true,
        false
    ),
    preset!(
        "ct-mip",
        [-3024, 0, -637.62, 0, 700, 1, 3071, 1],
        [-3024, 0, 0, 0, -637.62, 1, 1, 1, 700, 1, 1, 1, 3071, 1, 1, 1],
        [0.1, 0.9, 0.2, 10.0],
        true,
        false
    ),
    preset!(
        "ct-muscle",
        [-3024, 0, -155.407, 0, 217.641, 0.676471, 419.736, 0.833333, 3071, 0.803922],
        [
            -3024, 0, 0, 0, -155.407, 0.54902, 0.25098, 0.14902, 217.641, 0.882353, 0.603922,
            0.290196, 419.736, 1, 0.937033, 0.954531, 3071, 0.827451, 0.658824, 1
        ],
        [0.1, 0.9, 0.2, 10.0],
        true,
        false
    ),
    preset!(
        "ct-pulmonary-arteries",
        [
            -2048, 0, -568.625, 0, -364.081, 0.0714286, -244.813, 0.401786, 18.2775, 0.607143,
            447.798, 0.830357, 3592.73, 0.839286
        ],
        [
            -2048, 0, 0, 0, -568.625, 0, 0, 0, -364.081, 0.396078, 0.301961, 0.180392, -244.813,
            0.611765, 0.352941, 0.0705882, 18.2775, 0.843137, 0.0156863, 0.156863, 447.798,
            0.752941, 0.752941, 0.752941, 3592.73, 1, 1, 1
        ],
        [0.2, 1.0, 0.0, 1.0],
        true,
        false
    ),
    preset!(
        "ct-soft-tissue",
        [-2048, 0, -167.01, 0, -160, 1, 240, 1, 3661, 1],
        [
            -2048, 0, 0, 0, -167.01, 0, 0, 0, -160, 0.0556356, 0.0556356, 0.0556356, 240, 1, 1, 1,
            3661, 1, 1, 1
        ],
        [0.2, 1.0, 0.0, 1.0],
        false,
        false
    ),
    preset!(
        "mr-angio",
        [
            -2048, 0, 151.354, 0, 158.279, 0.4375, 190.112, 0.580357, 200.873, 0.732143, 3661,
            0.741071
        ],
        [
            -2048, 0, 0, 0, 151.354, 0, 0, 0, 158.279, 0.74902, 0.376471, 0, 190.112, 1, 0.866667,
            0.733333, 200.873, 0.937255, 0.937255, 0.937255, 3661, 1, 1, 1
        ],
        [0.2, 1.0, 0.0, 1.0],
        true,
        true
    ),
    preset!(
        "mr-default",
        [0, 0, 20, 0, 40, 0.15, 120, 0.3, 220, 0.375, 1024, 0.5],
        [
            0, 0, 0, 0, 20, 0.168627, 0, 0, 40, 0.403922, 0.145098, 0.0784314, 120, 0.780392,
            0.607843, 0.380392, 220, 0.847059, 0.835294, 0.788235, 1024, 1, 1, 1
        ],
        [0.2, 1.0, 0.0, 1.0],
        true,
        true
    ),
    preset!(
        "mr-mip",
        [0, 0, 98.3725, 0, 416.637, 1, 2800, 1],
        [0, 1, 1, 1, 98.3725, 1, 1, 1, 416.637, 1, 1, 1, 2800, 1, 1, 1],
        [0.2, 1.0, 0.0, 1.0],
        false,
        true
    ),
    preset!(
        "mr-t2-brain",
        [0, 0, 36.05, 0, 218.302, 0.171429, 412.406, 1, 641, 1],
        [
            0, 0, 0, 0, 98.7223, 0.956863, 0.839216, 0.192157, 412.406, 0, 0.592157, 0.807843, 641,
            1, 1, 1
        ],
        [0.3, 0.6, 0.5, 40.0],
        true,
        true
    ),
    preset!(
        "dti-fa-brain",
        // Slicer lists two points at 0 and two at 0.9950 (steps); they are merged here
        // (the second of each pair kept) because glint needs strictly increasing values.
        [0, 0, 0.3501, 0.0158, 0.49379, 0.7619, 0.6419, 1, 0.9920, 1, 0.9950, 0],
        [
            0, 1, 0, 0, 0.24974, 0.4941, 1, 0, 0.49949, 0, 0.9882, 1, 0.7492, 0.51764, 0, 1,
            0.9950, 1, 0, 0
        ],
        [0.3, 0.9, 0.5, 40.0],
        true,
        false
    ),
];

/// The preset called `name` (case-insensitive; Slicer's capitalised names work too).
pub fn preset(name: &str) -> Result<&'static Preset, RenderError> {
    let key = name.trim().to_ascii_lowercase();
    PRESETS
        .iter()
        .find(|p| p.name == key)
        .ok_or_else(|| RenderError::UnknownPreset {
            name: name.to_string(),
            known: PRESETS
                .iter()
                .map(|p| p.name)
                .collect::<Vec<_>>()
                .join(", "),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_is_valid() {
        for p in PRESETS {
            let tf = p
                .transfer_function(255.0)
                .unwrap_or_else(|e| panic!("{}: {e}", p.name));
            assert!(tf.validate().is_ok());
            assert!(p.material().validate().is_ok(), "{}", p.name);
        }
    }

    #[test]
    fn steep_presets_are_the_narrow_ramps() {
        // ct-soft-tissue: opacity 0 to 1 over -167..-160 HU; ct-lung over 0.15 per HU.
        for name in ["ct-soft-tissue", "ct-lung", "ct-fat", "mr-angio"] {
            let p = preset(name).unwrap();
            assert!(p.is_steep(), "{name}");
            assert_eq!(p.sampling(), Sampling::PreIntegrated, "{name}");
        }
        // Ramps of hundreds of HU, and the phantom's (0.02 of its 0..1 domain).
        for name in [
            "ct-bone",
            "ct-muscle",
            "mr-t2-brain",
            "mr-default",
            "phantom",
            "ct-aaa",
        ] {
            let p = preset(name).unwrap();
            assert!(!p.is_steep(), "{name}");
            assert_eq!(p.sampling(), Sampling::Point, "{name}");
        }
    }

    #[test]
    fn lookup_is_case_insensitive_and_errors_list_names() {
        assert_eq!(preset("CT-Bone").unwrap().name, "ct-bone");
        let err = preset("ct-bogus").unwrap_err().to_string();
        assert!(
            err.contains("ct-bogus") && err.contains("mr-t2-brain"),
            "{err}"
        );
    }

    #[test]
    fn relative_presets_scale_to_the_volume() {
        // MR-T2-Brain's opacity reaches 1 at 412.406 of 641; on a volume reaching 255
        // that is 412.406 * 255 / 641.
        let tf = preset("mr-t2-brain")
            .unwrap()
            .transfer_function(255.0)
            .unwrap();
        let x = 412.406 * 255.0 / 641.0;
        assert!((tf.opacity_at(x) - 1.0).abs() < 1e-9);
        assert!(tf.opacity_at(x - 5.0) < 1.0);
        // CT presets stay in HU.
        let bone = preset("ct-bone").unwrap().transfer_function(255.0).unwrap();
        assert!((bone.opacity_at(641.385) - 0.715686).abs() < 1e-9);
    }
}
