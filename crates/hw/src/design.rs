//! One design of any family (K_v, exact `cos^n`, Schlick) as a JSON-serialisable value,
//! its Verilog unit, and the error figures `glint hw pareto` and `glint hw check`
//! report for it (both call [`Design::errors`], so they agree by construction).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::hdl::{HdlUnit, KvUnit, Ports, PowParams, PowerUnit, SchlickParams, SchlickUnit};
use crate::{measure, Config, HwError, Input, Unit};

/// The interface every design of the exploration shares: cos Q1.14, n <= 1023.
pub const DESIGN_COS_BITS: u32 = 16;
/// Width of `n` in the exploration.
pub const DESIGN_N_BITS: u32 = 10;

/// The `n` ranges of the error columns (`cos^n`), as in `glint hw check`.
pub const N_RANGES: [(u32, u32); 4] = [(1, 15), (16, 63), (64, 255), (256, 1023)];

/// A design of one of the three families.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "family")]
pub enum Design {
    /// The K_v unit of a [`Config`].
    #[serde(rename = "kv")]
    Kv(Config),
    /// The log/exp `cos^n` unit.
    #[serde(rename = "pow")]
    Pow {
        /// Output code width.
        out_bits: u32,
        /// Its tables.
        params: PowParams,
    },
    /// The Schlick unit.
    #[serde(rename = "schlick")]
    Schlick {
        /// Output code width.
        out_bits: u32,
        /// Its divider widths.
        params: SchlickParams,
    },
}

/// The error figures of a design, in output LSBs (exhaustive, `k_s·I` at full scale).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DesignErrors {
    /// Against the design's own lobe (K_v or the minimax lobe: every code in [-1, 1];
    /// `cos^n` and Schlick's form: every code in [0, 1]), every `n`.
    pub lobe: f64,
    /// Against `cos^n` for the `n` of each of [`N_RANGES`], every code in [0, 1].
    pub power: [f64; 4],
    /// Against `cos^n` for every `n` including 0.
    pub power_all: f64,
}

impl DesignErrors {
    /// Against `cos^n` over `n` in 16..=1023 (the plots' error axis).
    pub fn power_16_up(&self) -> f64 {
        self.power[1].max(self.power[2]).max(self.power[3])
    }
}

impl Design {
    /// Parses a design: a JSON object with `"family"` (`kv`, `pow`, `schlick`), or a
    /// plain K_v [`Config`] (no `family` key), as `glint hw check --config` reads.
    pub fn from_json(text: &str) -> Result<Design, HwError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| HwError::Parse(e.to_string()))?;
        if value.get("family").is_some() {
            serde_json::from_value(value).map_err(|e| HwError::Parse(e.to_string()))
        } else {
            Ok(Design::Kv(Config::from_json(text)?))
        }
    }

    /// The design as one line of JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("a Design always serialises")
    }

    /// Family name.
    pub fn family(&self) -> &'static str {
        match self {
            Design::Kv(_) => "kv",
            Design::Pow { .. } => "pow",
            Design::Schlick { .. } => "schlick",
        }
    }

    /// The design with its output `out_bits` wide (every family): `glint hw check
    /// --out-bits`.
    pub fn with_out_bits(self, out_bits: u32) -> Design {
        match self {
            Design::Kv(config) => Design::Kv(Config { out_bits, ..config }),
            Design::Pow { params, .. } => Design::Pow { out_bits, params },
            Design::Schlick { params, .. } => Design::Schlick { out_bits, params },
        }
    }

    /// Output width.
    pub fn out_bits(&self) -> u32 {
        match self {
            Design::Kv(c) => c.out_bits,
            Design::Pow { out_bits, .. } | Design::Schlick { out_bits, .. } => *out_bits,
        }
    }

    fn ports(out_bits: u32) -> Ports {
        Ports {
            cos_bits: DESIGN_COS_BITS,
            n_bits: DESIGN_N_BITS,
            out_bits,
        }
    }

    /// The Verilog unit with its model (validates the design).
    pub fn hdl(&self) -> Result<Box<dyn HdlUnit + Send>, HwError> {
        Ok(match self {
            Design::Kv(c) => Box::new(KvUnit::new(Unit::new(c.clone())?)),
            Design::Pow { out_bits, params } => {
                Box::new(PowerUnit::with_params(Self::ports(*out_bits), *params)?)
            }
            Design::Schlick { out_bits, params } => {
                Box::new(SchlickUnit::with_params(Self::ports(*out_bits), *params)?)
            }
        })
    }

    /// The exhaustive error figures (see [`DesignErrors`]); ~1 s in a release build.
    pub fn errors(&self) -> Result<DesignErrors, HwError> {
        match self {
            Design::Kv(c) => {
                let unit = Unit::new(c.clone())?;
                let last = (1u32 << c.n_bits) - 1;
                let m = measure(&unit);
                Ok(DesignErrors {
                    lobe: m.worst_lobe(0..=last).error,
                    power: N_RANGES.map(|(a, b)| m.worst_power(a..=b.min(last)).error),
                    power_all: m.worst_power(0..=last).error,
                })
            }
            Design::Pow { .. } => {
                let u = self.hdl()?;
                Ok(errors_on_unit_interval(u.as_ref(), &|c, n| power(c, n)))
            }
            Design::Schlick { .. } => {
                let u = self.hdl()?;
                Ok(errors_on_unit_interval(u.as_ref(), &schlick))
            }
        }
    }
}

/// `c^n` with `0^0 = 1`.
fn power(c: f64, n: u32) -> f64 {
    c.powi(n as i32)
}

/// Schlick's `c / (n - n·c + c)`, 1 at `c = n = 0` (as the unit's clamp gives).
fn schlick(c: f64, n: u32) -> f64 {
    let n = f64::from(n);
    let den = n - n * c + c;
    if den <= 0.0 {
        1.0
    } else {
        c / den
    }
}

/// Errors of a unit whose lobe is defined on [0, 1]: every code in [0, 1], every `n`.
fn errors_on_unit_interval(
    unit: &dyn HdlUnit,
    lobe: &(dyn Fn(f64, u32) -> f64 + Sync),
) -> DesignErrors {
    let p = unit.ports();
    let one = 1i64 << (p.cos_bits - 2);
    let fs = crate::hdl::mask(p.out_bits);
    let fsf = fs as f64;
    let per_n: Vec<(f64, f64)> = (0..1u32 << p.n_bits)
        .into_par_iter()
        .map(|n| {
            let (mut el, mut ep) = (0.0f64, 0.0f64);
            for cos in 0..=one {
                let out = unit
                    .eval(&Input {
                        cos,
                        n,
                        ks: [fs; 3],
                    })
                    .rgb[0] as f64;
                let c = cos as f64 / one as f64;
                el = el.max((out - fsf * lobe(c, n)).abs());
                ep = ep.max((out - fsf * power(c, n)).abs());
            }
            (el, ep)
        })
        .collect();
    let range = |a: u32, b: u32| {
        per_n[a as usize..=(b as usize).min(per_n.len() - 1)]
            .iter()
            .map(|e| e.1)
            .fold(0.0, f64::max)
    };
    DesignErrors {
        lobe: per_n.iter().map(|e| e.0).fold(0.0, f64::max),
        power: N_RANGES.map(|(a, b)| range(a, b)),
        power_all: range(0, (per_n.len() - 1) as u32),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn with_out_bits_sets_every_familys_width() {
        let designs = [
            Design::Kv(Config::default()),
            Design::Pow {
                out_bits: 10,
                params: PowParams::default(),
            },
            Design::Schlick {
                out_bits: 10,
                params: SchlickParams::default(),
            },
        ];
        for d in designs {
            let family = d.family();
            let d = d.with_out_bits(7);
            assert_eq!((d.family(), d.out_bits()), (family, 7));
        }
    }

    #[test]
    fn plain_configs_and_tagged_designs_parse() {
        let d = Design::from_json(r#"{"v": 3, "square_frac": [12, 12, 12]}"#).unwrap();
        assert!(matches!(&d, Design::Kv(c) if c.v == 3));
        let p = Design::Pow {
            out_bits: 10,
            params: PowParams::default(),
        };
        assert_eq!(Design::from_json(&p.to_json()).unwrap(), p);
        let k = Design::Kv(Config::default());
        assert_eq!(Design::from_json(&k.to_json()).unwrap(), k);
        assert!(Design::from_json(r#"{"family": "pow", "out_bits": 8}"#).is_err());
        assert!(Design::from_json(r#"{"family": "nope"}"#).is_err());
        assert!(Design::from_json("[1]").is_err());
    }

    #[test]
    fn schlick_reference_by_hand() {
        assert_eq!(schlick(1.0, 100), 1.0);
        assert_eq!(schlick(0.0, 0), 1.0);
        // 0.5 / (10 - 5 + 0.5) = 1/11.
        assert!((schlick(0.5, 10) - 1.0 / 11.0).abs() < 1e-15);
    }
}
