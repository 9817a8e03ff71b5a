//! The stage-by-stage trace of one input as a table (what `glint hw eval` prints), with
//! the model's self-check: the functional model, a lone input through the pipeline and
//! the same input in a busy pipeline must agree.

use crate::{HwError, Input, Output, Pipeline, Unit};

/// One row of the trace table.
#[derive(Clone, Debug, PartialEq)]
pub struct TraceRow {
    /// Stage name, e.g. `ROM1 a(n)`.
    pub stage: String,
    /// Fixed-point format, e.g. `UQ6.12`.
    pub format: String,
    /// The register's code, decimal.
    pub code: String,
    /// The register's code, hexadecimal at its width.
    pub hex: String,
    /// The real value (and, for outputs, the errors against the exact lobe and `cos^n`).
    pub value: String,
}

/// The trace table of one input and its output.
#[derive(Clone, Debug, PartialEq)]
pub struct TraceTable {
    /// One row per register.
    pub rows: Vec<TraceRow>,
    /// The output, agreed by the three models.
    pub output: Output,
}

fn all_ones(bits: u32) -> u64 {
    u64::MAX
        .checked_shr(64u32.saturating_sub(bits))
        .unwrap_or(0)
}

fn hex(x: u64, bits: u32) -> String {
    format!(
        "0x{:0w$x}",
        x & all_ones(bits),
        w = bits.div_ceil(4) as usize
    )
}

fn val(x: u64, frac: u32) -> String {
    format!("{:.12}", x as f64 / 2f64.powi(frac as i32))
}

impl Unit {
    /// Checks that the functional model, the pipeline with the input alone and the
    /// pipeline busy with neighbours on both sides give the same output.
    fn self_check(&self, input: &Input, traced: Output) -> Result<(), HwError> {
        let functional = self.eval(input)?;
        let mut pipe = Pipeline::new(self);
        let neighbour = Input { n: 0, ..*input };
        pipe.clock(Some(neighbour))?;
        pipe.clock(Some(*input))?;
        let mut busy = None;
        for _ in 0..self.latency() {
            busy = pipe.clock(Some(neighbour))?;
        }
        if functional != traced || busy != Some(traced) {
            return Err(HwError::Internal(format!(
                "functional model {functional:?}, lone pipeline {traced:?} and busy pipeline {busy:?} disagree"
            )));
        }
        Ok(())
    }

    /// Every register's value as `input` passes (see [`Unit::trace`]), after the
    /// self-check.
    pub fn trace_table(&self, input: &Input) -> Result<TraceTable, HwError> {
        let trace = self.trace(input)?;
        self.self_check(input, trace.output)?;
        let f = self.formats();
        let cfg = self.config();
        let c = self.cos_value(input.cos);
        let row =
            |stage: &str, format: String, code: String, hex: String, value: String| TraceRow {
                stage: stage.to_string(),
                format,
                code,
                hex,
                value,
            };
        let (r1, p, b) = (trace.rom_sm1, trace.mul.p, trace.base);
        let exact_a = self.rom().exact()[input.n as usize];
        let mut rows = vec![
            row(
                "RG1 cos",
                format!("Q1.{} signed", f.cos_frac),
                input.cos.to_string(),
                hex(input.cos as u64, cfg.cos_bits),
                format!("{c:.12}"),
            ),
            row(
                "RG2 n",
                format!("U{}", cfg.n_bits),
                input.n.to_string(),
                hex(input.n.into(), cfg.n_bits),
                input.n.to_string(),
            ),
            row(
                "ROM1 a(n)",
                format!("UQ{}.{}", f.coef_int, f.coef_frac),
                r1.a.to_string(),
                hex(r1.a, cfg.coef_bits),
                format!("{} (exact {exact_a:.12})", val(r1.a, f.coef_frac)),
            ),
            row(
                "Sm1 1-cos",
                format!("UQ2.{}", f.t_frac),
                r1.t.to_string(),
                hex(r1.t, f.t_frac + 2),
                val(r1.t, f.t_frac),
            ),
            row(
                "MUL a(1-cos)",
                format!("UQ{}.{}", f.mul_int, f.mul_frac),
                p.to_string(),
                hex(p, f.mul_bits()),
                val(p, f.mul_frac),
            ),
            row(
                "Sm2 1-p",
                format!("Q{}.{} signed", f.mul_int, f.mul_frac),
                b.diff.to_string(),
                hex(b.diff as u64, f.sm2_bits()),
                format!("{:.12}", b.diff as f64 / 2f64.powi(f.mul_frac as i32)),
            ),
            row(
                "SW base",
                format!("UQ1.{}", f.mul_frac),
                b.b.to_string(),
                hex(b.b, f.mul_frac + 1),
                val(b.b, f.mul_frac),
            ),
        ];
        for (k, sq) in trace.squares.iter().enumerate() {
            let fr = f.square_frac[k];
            rows.push(row(
                &format!("BMUL^{}", 1u64 << (k + 1)),
                format!("UQ1.{fr}"),
                sq.s.to_string(),
                hex(sq.s, fr + 1),
                val(sq.s, fr),
            ));
        }
        let base = 1.0 - exact_a * (1.0 - c);
        let lobe = if base <= 0.0 {
            0.0
        } else {
            base.powi(1 << cfg.v)
        };
        let power = c.max(0.0).powf(f64::from(input.n));
        for (k, name) in ["R", "G", "B"].iter().enumerate() {
            let ks = input.ks[k] as f64;
            let out = trace.output.rgb[k];
            rows.push(row(
                &format!("MUL{} {name}", k + 1),
                format!("U{}", cfg.out_bits),
                out.to_string(),
                hex(out, cfg.out_bits),
                format!(
                    "exact lobe·ks {:.4} (err {:+.4} LSB), cos^n·ks {:.4} (err {:+.4} LSB)",
                    lobe * ks,
                    out as f64 - lobe * ks,
                    power * ks,
                    out as f64 - power * ks
                ),
            ));
        }
        Ok(TraceTable {
            rows,
            output: trace.output,
        })
    }
}
