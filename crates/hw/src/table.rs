//! The unit as a renderer's lobe: for one `n` the output depends only on the cosine
//! code, so the unit is evaluated once for every code and looked up per sample
//! ([`glint_lobe::CosTable`]).

use glint_lobe::{CosTable, TableError};

use crate::{HwError, Unit};

/// Why [`Unit::cos_table`] could not build a table.
#[derive(Debug, thiserror::Error)]
pub enum CosTableError {
    /// `n` does not fit the unit's `n` input.
    #[error(transparent)]
    Unit(#[from] HwError),
    /// The cosine input is too wide for a table (see [`glint_lobe::MAX_TABLE_FRAC_BITS`]).
    #[error("the unit's cosine input cannot be tabulated")]
    Table(#[from] TableError),
}

impl Unit {
    /// The integer `n` input for a real shininess: `n` rounded to nearest, which must
    /// fit the `n_bits`-wide RG2 register.
    pub fn n_code(&self, n: f64) -> Result<u32, HwError> {
        let max = (1u64 << self.config().n_bits) - 1;
        let r = n.round();
        if !r.is_finite() || r < 0.0 || r > max as f64 {
            return Err(HwError::Input(format!(
                "n = {n} does not fit the {}-bit n input (0 ..= {max})",
                self.config().n_bits
            )));
        }
        Ok(r as u32)
    }

    /// The unit's specular value for shininess input `n` at every cosine code
    /// `-2^f ..= 2^f` (`f` = [`crate::Formats::cos_frac`]): the R output code for
    /// `k_s·I` at full scale, over the full scale, i.e.
    /// `eval(Input { cos: code, n, ks: [full; 3] }).rgb[0] / full` rounded to f32.
    /// A renderer evaluates it at `c` as `eval` at `cos_code(c)` (same rounding, `c`
    /// clamped to `[-1, 1]`).
    ///
    /// The table carries `n` and the unit's `v`
    /// ([`CosTable::with_shininess`](glint_lobe::CosTable::with_shininess)), so a path
    /// tracer can sample it as K_v(n) (`glint_lobe::Specular::sampler`).
    ///
    /// Errors if `n` does not fit `n_bits` or the cosine has more than
    /// [`glint_lobe::MAX_TABLE_FRAC_BITS`] fraction bits.
    pub fn cos_table(&self, n: u32) -> Result<CosTable, CosTableError> {
        let full = self.full_scale();
        // Checks n (and a valid cos code) once, so the lean path below may be used.
        self.check_input(&crate::Input {
            cos: 0,
            n,
            ks: [full; 3],
        })?;
        let full_f = full as f64;
        Ok(CosTable::from_fn(self.formats().cos_frac, |code| {
            let out = self.output_code(self.lobe_code(i64::from(code), n), full);
            (out as f64 / full_f) as f32
        })?
        .with_shininess(f64::from(n), self.config().v))
    }
}

#[cfg(test)]
mod tests {
    use crate::{Coefficients, Config, Input, Unit};

    /// `Unit::eval`'s output over full scale for one code: what the table must hold.
    fn model(unit: &Unit, code: i64, n: u32) -> f32 {
        let full = unit.full_scale();
        let out = unit
            .eval(&Input {
                cos: code,
                n,
                ks: [full; 3],
            })
            .unwrap();
        assert_eq!(out.rgb, [out.rgb[0]; 3]);
        (out.rgb[0] as f64 / full as f64) as f32
    }

    /// Every cosine code of `unit`, for each `n`: the table equals the model bit for bit.
    fn check_every_code(unit: &Unit, ns: &[u32]) {
        let f = unit.formats().cos_frac;
        let one = 1i64 << f;
        for &n in ns {
            let table = unit.cos_table(n).unwrap();
            assert_eq!(table.frac_bits(), f);
            assert_eq!(table.shininess(), Some((f64::from(n), unit.config().v)));
            let mut nonzero = 0;
            for code in -one..=one {
                let want = model(unit, code, n);
                let got = table.value(code as i32);
                assert_eq!(got.to_bits(), want.to_bits(), "n = {n}, code {code}");
                // Looked up by the real cosine, as the renderer does.
                let c = (code as f64 / one as f64) as f32;
                assert_eq!(table.eval(c).to_bits(), want.to_bits(), "n = {n}, c = {c}");
                nonzero += usize::from(want > 0.0);
            }
            // Not a vacuous comparison: the lobe is 1 at c = 1 and has a visible body.
            assert_eq!(model(unit, one, n), 1.0, "n = {n}");
            assert!(nonzero >= 2, "n = {n}: only {nonzero} nonzero codes");
        }
    }

    #[test]
    fn table_equals_the_model_for_every_code_default_unit() {
        let unit = Unit::new(Config::default()).unwrap();
        // 0, 2^v, a typical shininess, and the largest n the 10-bit input takes.
        check_every_code(&unit, &[0, 1, 16, 100, 1023]);
    }

    #[test]
    fn table_equals_the_model_for_every_code_other_units() {
        let configs = [
            // 12-bit output, truncating multipliers, narrow cosine.
            Config {
                cos_bits: 12,
                out_bits: 12,
                out_round: crate::Rounding::Truncate,
                mul_round: crate::Rounding::Truncate,
                ..Config::default()
            },
            // The minimax ROM (7-bit n keeps the coefficient search short).
            Config {
                coefficients: Coefficients::Minimax,
                n_bits: 7,
                ..Config::default()
            },
            // v = 2, 10-bit output.
            Config {
                v: 2,
                square_frac: vec![14, 12],
                out_bits: 10,
                ..Config::default()
            },
        ];
        for config in configs {
            let unit = Unit::new(config).unwrap();
            let max = (1u32 << unit.config().n_bits) - 1;
            let two_v = 1u32 << unit.config().v;
            check_every_code(&unit, &[0, two_v, max]);
        }
    }

    #[test]
    fn the_default_units_table_is_sampled_as_k_v_alone() {
        // The unit's table stays within glint_lobe::DOMINANCE times K_v wherever it
        // is lit, so sampling it as K_v needs no defensive share.
        let unit = Unit::new(Config::default()).unwrap();
        for n in [0, 1, 7, 16, 60, 100, 1023] {
            let table = glint_lobe::Specular::from(unit.cos_table(n).unwrap());
            let sampler = table.sampler().unwrap();
            assert!(!sampler.is_defensive(), "n = {n}");
        }
    }

    #[test]
    fn cosines_between_codes_round_as_cos_code_does() {
        let unit = Unit::new(Config::default()).unwrap();
        let table = unit.cos_table(60).unwrap();
        for i in 0..=40_000 {
            let c = 0.8f32 + 0.2 * i as f32 / 40_000.0;
            let code = unit.cos_code(f64::from(c)).unwrap();
            assert_eq!(table.eval(c), model(&unit, code, 60), "c = {c}");
        }
        // Outside [-1, 1]: clamped, as the lobes of glint-lobe do.
        assert_eq!(table.eval(1.5), 1.0);
        assert_eq!(table.eval(-1.5), model(&unit, -(1 << 14), 60));
        assert_eq!(table.eval(f32::NAN), 0.0);
    }

    #[test]
    fn bad_n_and_wide_cosines_are_rejected() {
        let unit = Unit::new(Config::default()).unwrap();
        assert!(unit.cos_table(1024).is_err());
        assert_eq!(unit.n_code(99.6).unwrap(), 100);
        assert!(unit.n_code(1023.4).is_ok());
        assert!(unit.n_code(1023.6).is_err());
        assert!(unit.n_code(-1.0).is_err());
        assert!(unit.n_code(f64::NAN).is_err());
        let wide = Unit::new(Config {
            cos_bits: 24,
            ..Config::default()
        })
        .unwrap();
        assert!(matches!(
            wide.cos_table(10),
            Err(super::CosTableError::Table(_))
        ));
    }
}
