//! The specular lobe of a scene: one of glint-lobe's closed forms or the hardware unit.

use glint_hw::Config as HwConfig;
use glint_lobe::{Geometry, Lobe, LobeKind, Specular};
use serde::{Deserialize, Serialize};

use glint_core::RenderError;

use crate::hwlobe::HwCache;

/// Which lobe a scene uses: one of glint-lobe's closed-form lobes, evaluated in f32,
/// or the bit-accurate hardware unit of glint-hw. In scene JSON and on the command line
/// it is a name: a [`LobeKind`]'s (`exact`, `k`, ...) or `hw`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SceneLobe {
    /// A closed-form lobe of glint-lobe.
    Float(LobeKind),
    /// The hardware unit of [`LobeSpec::hw`]: per sample, the cosine is quantised to
    /// the unit's input code, n rounded to its integer input, and the specular value is
    /// the unit's output code over full scale, as `glint_hw::Unit::eval` gives it.
    Hw,
}

impl SceneLobe {
    /// Every lobe, in the order `--help` lists them: glint-lobe's, then `hw`.
    pub const ALL: [SceneLobe; 7] = [
        SceneLobe::Float(LobeKind::Exact),
        SceneLobe::Float(LobeKind::EnergyFit),
        SceneLobe::Float(LobeKind::SlopeFit),
        SceneLobe::Float(LobeKind::Schlick),
        SceneLobe::Float(LobeKind::Gauss),
        SceneLobe::Float(LobeKind::Minimax),
        SceneLobe::Hw,
    ];

    /// The name users type (`exact`, `k`, ..., `hw`).
    pub fn name(self) -> &'static str {
        match self {
            SceneLobe::Float(kind) => kind.name(),
            SceneLobe::Hw => "hw",
        }
    }

    /// The closed-form lobe, `None` for the unit.
    pub fn float(self) -> Option<LobeKind> {
        match self {
            SceneLobe::Float(kind) => Some(kind),
            SceneLobe::Hw => None,
        }
    }
}

impl From<LobeKind> for SceneLobe {
    fn from(kind: LobeKind) -> Self {
        SceneLobe::Float(kind)
    }
}

impl std::fmt::Display for SceneLobe {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for SceneLobe {
    type Err = RenderError;
    /// A [`LobeKind`] name (and its aliases) or `hw`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.trim().eq_ignore_ascii_case("hw") {
            return Ok(SceneLobe::Hw);
        }
        s.parse::<LobeKind>().map(SceneLobe::Float).map_err(|_| {
            RenderError::Parameter(format!(
                "unknown lobe '{s}': expected one of exact, k, g, schlick, gauss, minimax, hw"
            ))
        })
    }
}

/// The `v` of the default lobe, K_4 (the paper's).
const DEFAULT_V: u32 = 4;

/// The specular lobe of a scene.
///
/// For a `hw` lobe, the unit is [`LobeSpec::hw`] (resolution writes
/// `glint_hw::Config::default()` there when it is unset) and `v` is the unit's: scene
/// JSON that leaves `v` out takes `hw.v`, and a `v` that differs from it is refused
/// when the scene is resolved ([`RenderError::HwV`]). Other lobes ignore `hw` (and keep
/// it, so a front end may switch between `k` and `hw` without losing the unit).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "LobeFields")]
pub struct LobeSpec {
    /// Which lobe.
    #[serde(with = "by_name")]
    pub kind: SceneLobe,
    /// Shininess n (default: the preset's specular power).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n: Option<f64>,
    /// The power fits raise their base to 2^v (for `hw`: the unit's `v`).
    pub v: u32,
    /// Phong (R·V) or Blinn (N·H).
    #[serde(with = "by_name")]
    pub geometry: Geometry,
    /// The hardware unit of a `hw` lobe: every field of `glint_hw::Config`, missing
    /// ones taking the default's (`glint hw eval --print-config`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hw: Option<HwConfig>,
}

impl Default for LobeSpec {
    /// The paper's lobe: K_4, Phong geometry, n from the preset.
    fn default() -> Self {
        LobeSpec {
            kind: SceneLobe::Float(LobeKind::EnergyFit),
            n: None,
            v: DEFAULT_V,
            geometry: Geometry::Phong,
            hw: None,
        }
    }
}

impl LobeSpec {
    /// The hardware unit `config` as a lobe (its `v`, n from the preset, Phong).
    pub fn hw(config: HwConfig) -> LobeSpec {
        LobeSpec {
            kind: SceneLobe::Hw,
            v: config.v,
            hw: Some(config),
            ..LobeSpec::default()
        }
    }

    /// Switches to the lobe `kind`. A `hw` lobe squares as often as its unit does, so
    /// it takes the unit's v (the default unit's when none is set) unless `v` says
    /// otherwise (a contradicting `v` is refused when the scene is resolved); other
    /// lobes keep theirs unless `v` is given.
    pub fn set_kind(&mut self, kind: SceneLobe, v: Option<u32>) {
        self.kind = kind;
        match (kind, v) {
            (_, Some(v)) => self.v = v,
            (SceneLobe::Hw, None) => {
                self.v = self.hw.as_ref().map_or(HwConfig::default().v, |c| c.v);
            }
            (SceneLobe::Float(_), None) => {}
        }
    }
}

/// [`LobeSpec`] as scene JSON gives it: `v` may be left out, and then follows the
/// lobe (the unit's for `hw`, else [`DEFAULT_V`]).
#[derive(Deserialize)]
#[serde(default, deny_unknown_fields)]
struct LobeFields {
    #[serde(with = "by_name")]
    kind: SceneLobe,
    n: Option<f64>,
    v: Option<u32>,
    #[serde(with = "by_name")]
    geometry: Geometry,
    hw: Option<HwConfig>,
}

impl Default for LobeFields {
    fn default() -> Self {
        let d = LobeSpec::default();
        LobeFields {
            kind: d.kind,
            n: d.n,
            v: None,
            geometry: d.geometry,
            hw: d.hw,
        }
    }
}

impl From<LobeFields> for LobeSpec {
    fn from(f: LobeFields) -> Self {
        let v = f.v.unwrap_or(match (f.kind, &f.hw) {
            (SceneLobe::Hw, Some(config)) => config.v,
            (SceneLobe::Hw, None) => HwConfig::default().v,
            (SceneLobe::Float(_), _) => DEFAULT_V,
        });
        LobeSpec {
            kind: f.kind,
            n: f.n,
            v,
            geometry: f.geometry,
            hw: f.hw,
        }
    }
}

impl LobeSpec {
    /// The specular term for shininess `n`: the closed-form lobe, or the unit's table
    /// (from `cache`), writing the default unit into [`LobeSpec::hw`] when unset.
    pub(crate) fn specular(&mut self, n: f64, cache: &HwCache) -> Result<Specular, RenderError> {
        match self.kind {
            SceneLobe::Float(kind) => Ok(Lobe::<f32>::new(kind, n, self.v)?.into()),
            SceneLobe::Hw => {
                let config = self.hw.get_or_insert_with(HwConfig::default);
                if self.v != config.v {
                    return Err(RenderError::HwV {
                        lobe: self.v,
                        unit: config.v,
                    });
                }
                Ok(Specular::Table(cache.table(config, n)?))
            }
        }
    }
}

/// Serde through a type's name (`FromStr` and `Display`), for glint-lobe's enums,
/// which do not depend on serde.
mod by_name {
    use std::fmt::Display;
    use std::str::FromStr;

    use serde::{de::Error, Deserialize, Deserializer, Serializer};

    pub fn serialize<T: Display, S: Serializer>(x: &T, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(x)
    }

    pub fn deserialize<'de, T, D>(d: D) -> Result<T, D::Error>
    where
        T: FromStr,
        T::Err: Display,
        D: Deserializer<'de>,
    {
        let name = String::deserialize(d)?;
        name.parse().map_err(D::Error::custom)
    }
}
