//! An exact `cos^n` unit for comparison: `cos^n = 2^(-n·L)`, `L = -log2(cos)`, with a
//! log2 table, one multiplier and an exp2 table, each table linearly interpolated.
//! This is the approach of published specular hardware (Harris' log/antilog units;
//! see `docs/hardware.md`); every width below was chosen so that the exhaustive error
//! against `cos^n` stays within 1 output LSB (measured by
//! [`HdlUnit::max_error_vs_power`], tested in `tests/hdl.rs`).
//!
//! | stage | logic before the register | register |
//! |---|---|---|
//! | 0 | (inputs) | `cos`, `n`, `ks` |
//! | 1 | clamp `x = cos` to `[0, 1]` (UQ1.14); normalise `x = 2^-e (1 + m)` | `e` (4 bits), `m` (UQ0.14), flags `x = 0`, `n = 0` |
//! | 2 | log table at `m[13:5]` (synchronous) | `G`, `D`, `r = m[4:0]` |
//! | 3 | `g = G - round(D·r / 2^5)`; `L = e - 1 + g` | `L`, UQ4.20 |
//! | 4 | `y = n·L` | `y`, UQ14.20 |
//! | 5 | exp table at `y[19:12]` (synchronous); `y >= 10`? | `E`, `DE`, `w = y[11:0]`, `k = floor(y)`, flag |
//! | 6 | `lobe = (E - round(DE·w / 2^12)) >> k`, or 1 (`n = 0`), or 0 | `lobe`, UQ1.16 |
//! | 7 | `round(lobe · ks)` | R, G, B |
//!
//! The log table holds `g(m) = 1 - log2(1 + m)` at `m = i/512` (so `L = e - 1 + g`
//! needs no sign), the exp table `2^(-u)` at `u = j/256`; each word also holds the
//! difference to the next entry, the slope of the interpolation.
//!
//! Those are the defaults of [`PowParams`]; the design space of `glint hw pareto` varies
//! the table sizes, the fraction widths and whether each table is interpolated (a table
//! without interpolation holds the function at the middle of each segment). The
//! numbers in the table above are the defaults'.

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use super::vlog::{header, product, requantize, rgb_stage, unused_ok, valid_and_ks};
use super::{HdlFile, HdlUnit, Ports};
use crate::fixed::requantize as rq;
use crate::{HwError, Input, Output, Rounding};

/// Fraction bits of the `cos` input this unit is designed for (Q1.14).
const COS_FRAC: u32 = 14;
/// `y = n·L >= 2^EXP_SHIFT_BITS` means `cos^n < 2^-16`: the lobe is 0. Shifts of up
/// to 15 are applied.
const EXP_SHIFT_BITS: u32 = 4;
/// Clocks from the input registers to the output registers (stages 1..=7).
const LATENCY: u32 = 7;
/// Largest table address (4096 words), to keep synthesis of the tables as logic short.
pub const MAX_POW_INDEX: u32 = 12;

/// The widths of the log/exp unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PowParams {
    /// Address bits of the log table (`2^log_index` segments of the mantissa).
    pub log_index: u32,
    /// Fraction bits of `g` and `L = -log2 cos` (UQ4.log_frac).
    pub log_frac: u32,
    /// Interpolate the log table linearly (a slope field per word, one multiplier).
    pub log_interp: bool,
    /// Address bits of the exp table (segments of the fraction of `y = n·L`).
    pub exp_index: u32,
    /// Fraction bits of the exp table and of the lobe (UQ1.exp_frac).
    pub exp_frac: u32,
    /// Interpolate the exp table linearly.
    pub exp_interp: bool,
}

impl Default for PowParams {
    /// The comparison unit of `glint hw synth`: 512 + 256 interpolated words, within 1
    /// LSB of `cos^n` at 8 and 10 bits (0.55 LSB at 8).
    fn default() -> Self {
        PowParams {
            log_index: 9,
            log_frac: 20,
            log_interp: true,
            exp_index: 8,
            exp_frac: 16,
            exp_interp: true,
        }
    }
}

impl PowParams {
    /// Checks the ranges the generator supports.
    pub fn validate(&self) -> Result<(), HwError> {
        let bad = |what: String| Err(HwError::Unsupported(format!("cos^n unit: {what}")));
        if self.log_index == 0 || self.log_index > MAX_POW_INDEX {
            return bad(format!(
                "log_index = {} (expected 1..={MAX_POW_INDEX})",
                self.log_index
            ));
        }
        if self.exp_index == 0 || self.exp_index > MAX_POW_INDEX {
            return bad(format!(
                "exp_index = {} (expected 1..={MAX_POW_INDEX})",
                self.exp_index
            ));
        }
        if !(8..=28).contains(&self.log_frac) || self.exp_index >= self.log_frac {
            return bad(format!(
                "log_frac = {} (expected 8..=28 and more than exp_index = {})",
                self.log_frac, self.exp_index
            ));
        }
        if !(4..=24).contains(&self.exp_frac) {
            return bad(format!("exp_frac = {} (expected 4..=24)", self.exp_frac));
        }
        Ok(())
    }

    /// Words of both tables times their widths.
    pub fn rom_bits(&self) -> u64 {
        let u = PowerUnit::with_params(
            Ports {
                cos_bits: 16,
                n_bits: 10,
                out_bits: 8,
            },
            *self,
        );
        u.map_or(0, |u| u.rom_bits())
    }
}

/// One table: `(value, slope = value - next value)` per word.
type PowTable = Vec<(u64, u64)>;

/// The log/exp `cos^n` unit (see the module documentation).
#[derive(Clone, Debug)]
pub struct PowerUnit {
    ports: Ports,
    params: PowParams,
    log: PowTable,
    exp: PowTable,
    log_slope_bits: u32,
    exp_slope_bits: u32,
}

/// Bits of the largest slope (0 without interpolation).
fn slope_bits(t: &[(u64, u64)], interp: bool) -> u32 {
    if !interp {
        return 0;
    }
    (64 - t.iter().map(|w| w.1).max().unwrap_or(0).leading_zeros()).max(1)
}

impl PowerUnit {
    /// Module name, and stem of the file names.
    pub const MODULE: &'static str = "glint_pow";

    /// The unit for `ports` with the default tables ([`PowParams::default`]).
    pub fn new(ports: Ports) -> Result<PowerUnit, HwError> {
        PowerUnit::with_params(ports, PowParams::default())
    }

    /// The unit for `ports` with the given tables; designed for a Q1.14 `cos` (16
    /// bits), `n_bits <= 10`, `out_bits <= 10`.
    pub fn with_params(ports: Ports, params: PowParams) -> Result<PowerUnit, HwError> {
        if ports.cos_bits != COS_FRAC + 2 || ports.n_bits > 10 || ports.out_bits > 10 {
            return Err(HwError::Unsupported(format!(
                "the cos^n unit is designed for cos_bits = 16, n_bits <= 10, out_bits <= 10 (got {}, {}, {})",
                ports.cos_bits, ports.n_bits, ports.out_bits
            )));
        }
        params.validate()?;
        // Interpolated tables hold the grid points; plain ones the segment middles.
        // The plain log table's first word holds g(0) = 1 itself, not the middle of
        // its segment: L = e - 1 + g must not go below 0 at cos = 1 (e = 0, m = 0).
        let table = |count: u32,
                     frac: u32,
                     interp: bool,
                     edge_first: bool,
                     f: &dyn Fn(f64) -> f64|
         -> PowTable {
            let at = |x: f64| (f(x / f64::from(count)) * 2f64.powi(frac as i32)).round() as u64;
            (0..count)
                .map(|i| {
                    if interp {
                        let (a, b) = (at(f64::from(i)), at(f64::from(i + 1)));
                        (a, a - b)
                    } else if i == 0 && edge_first {
                        (at(0.0), 0)
                    } else {
                        (at(f64::from(i) + 0.5), 0)
                    }
                })
                .collect()
        };
        let p = params;
        let log = table(1 << p.log_index, p.log_frac, p.log_interp, true, &|m| {
            1.0 - (1.0 + m).log2()
        });
        let exp = table(1 << p.exp_index, p.exp_frac, p.exp_interp, false, &|u| {
            (-u).exp2()
        });
        Ok(PowerUnit {
            ports,
            params,
            log_slope_bits: slope_bits(&log, p.log_interp),
            exp_slope_bits: slope_bits(&exp, p.exp_interp),
            log,
            exp,
        })
    }

    /// The table widths.
    pub fn params(&self) -> PowParams {
        self.params
    }

    /// Mantissa bits below the log table's address (the interpolation fraction).
    fn log_low(&self) -> u32 {
        COS_FRAC.saturating_sub(self.params.log_index)
    }

    /// The lobe code, UQ1.exp_frac: the datapath of stages 1..=6.
    pub fn lobe_code(&self, cos: i64, n: u32) -> u64 {
        let p = &self.params;
        let one = 1i64 << COS_FRAC;
        let x = cos.clamp(0, one) as u64;
        if n == 0 {
            return 1 << p.exp_frac;
        }
        if x == 0 {
            return 0;
        }
        // Stage 1: x = 2^(14-e) (1 + m), leading one moved to bit 14.
        let e = u64::from(x.leading_zeros()) - (63 - u64::from(COS_FRAC));
        let m = (x << e) & ((1 << COS_FRAC) - 1);
        // Stages 2-3: g = 1 - log2(1 + m), L = e - 1 + g = -log2(x).
        let low = self.log_low();
        let (g0, d) = self.log[(m >> low) as usize];
        let g = if p.log_interp && low > 0 {
            let r = m & ((1 << low) - 1);
            g0 - rq(u128::from(d * r), low, 0, Rounding::Nearest) as u64
        } else {
            g0
        };
        let l = (e << p.log_frac) + g - (1 << p.log_frac);
        // Stage 4: y = n L.
        let y = u64::from(n) * l;
        // Stages 5-6.
        let k = y >> p.log_frac;
        if k >= 1 << EXP_SHIFT_BITS {
            return 0;
        }
        let u = y & ((1 << p.log_frac) - 1);
        let wbits = p.log_frac - p.exp_index;
        let (e0, de) = self.exp[(u >> wbits) as usize];
        let ev = if p.exp_interp {
            let w = u & ((1 << wbits) - 1);
            e0 - rq(u128::from(de * w), wbits, 0, Rounding::Nearest) as u64
        } else {
            e0
        };
        ev >> k
    }

    fn hex(&self, table: &[(u64, u64)], value_bits: u32, slope_bits: u32, what: &str) -> String {
        let digits = (value_bits + slope_bits).div_ceil(4) as usize;
        let mut s = format!(
            "// glint {}: {what}\n// {} words of {} bits: value (high {value_bits} bits), slope = value - next value (low {slope_bits} bits)\n",
            Self::MODULE,
            table.len(),
            value_bits + slope_bits
        );
        for &(v, d) in table {
            let _ = writeln!(s, "{:0digits$x}", (v << slope_bits) | d);
        }
        s
    }

    // shape: emitter (the Verilog module, written line by line)
    fn module_text(&self) -> String {
        let p = self.ports;
        let m = Self::MODULE;
        let q = self.params;
        let (lf, li, ls) = (q.log_frac, q.log_index, self.log_slope_bits);
        let (ef, ei, es) = (q.exp_frac, q.exp_index, self.exp_slope_bits);
        let low = self.log_low();
        let wbits = lf - ei;
        let lw = lf + 4; // L: UQ4.log_frac
        let yw = lw + p.n_bits; // y: UQ(4+n_bits).log_frac
        let mut s =
            format!(
            "// {m}: an exact cos^n specular unit for comparison (log2 table, multiplier, exp2\n\
// table), generated by glint-hw. Verilog-2005.\n\
//   cos^n = 2^(-n L),  L = -log2(cos);  R, G, B = round(cos^n * k_s*I)\n\
// Tables: log {} words, UQ1.{lf}, {}; exp {} words, UQ1.{ef}, {}.\n\
// Latency {LATENCY} clocks, one input per clock. cos is clamped to [0, 1]; n = 0 gives 1.\n",
            1u32 << li,
            if q.log_interp { "interpolated" } else { "segment middles" },
            1u32 << ei,
            if q.exp_interp { "interpolated" } else { "segment middles" },
        );
        s += &header(m, p);
        s += &valid_and_ks(LATENCY, p);
        let m1_decl = "    reg [13:0] m1;\n".to_string();
        let r2_decl = if q.log_interp {
            format!("    reg [{}:0] r2;\n", low - 1)
        } else {
            String::new()
        };
        let r2_load = if q.log_interp {
            format!("        r2 <= m1[{}:0];\n", low - 1)
        } else {
            String::new()
        };
        let _ = write!(
            s,
            "    // Stage 0: input registers.\n\
    reg [15:0] cos0;\n\
    reg [{n1}:0] n0;\n\
    always @(posedge clk) begin\n\
        cos0 <= cos_in;\n\
        n0 <= n_in;\n\
    end\n\n\
    // Stage 1: x = cos clamped to [0, 1], UQ1.14; x = 2^-e (1 + m): e = leading zeros\n\
    // of x in 15 bits, m = x << e without its leading one, UQ0.14.\n\
    wire [14:0] x = cos0[15] ? 15'd0 : (cos0[14] ? 15'd16384 : cos0[14:0]);\n\
    reg [3:0] lz;\n\
    integer i;\n\
    always @(*) begin\n\
        lz = 4'd15;\n\
        for (i = 0; i < 15; i = i + 1)\n\
            if (x[i]) lz = 4'd14 - i[3:0];\n\
    end\n\
    /* verilator lint_off UNUSEDSIGNAL */\n\
    wire [14:0] xs = x << lz;\n\
    /* verilator lint_on UNUSEDSIGNAL */\n\
    reg [3:0] e1;\n\
{m1}\
    reg zero1, one1;\n\
    reg [{n1}:0] n1;\n\
    always @(posedge clk) begin\n\
        e1 <= lz;\n\
        m1 <= xs[13:0];\n\
        zero1 <= (x == 15'd0);\n\
        one1 <= (n0 == {nb}'d0);\n\
        n1 <= n0;\n\
    end\n\n\
    // Stage 2: log table (synchronous read) at m[13:{low}]: word = {{G, D}},\n\
    // G = 1 - log2(1 + m) UQ1.{lf}{slope}.\n\
    reg [{lw1}:0] log_rom [0:{lmax}];\n\
    initial $readmemh(\"{m}_log.hex\", log_rom);\n\
    reg [{lw1}:0] log2w;\n\
{r2_decl}\
    reg [3:0] e2;\n\
    reg zero2, one2;\n\
    reg [{n1}:0] n2;\n\
    always @(posedge clk) begin\n\
        log2w <= log_rom[m1[13:{low}]];\n\
{r2_load}\
        e2 <= e1;\n\
        zero2 <= zero1;\n\
        one2 <= one1;\n\
        n2 <= n1;\n\
    end\n\n",
            n1 = p.n_bits - 1,
            nb = p.n_bits,
            m1 = if q.log_interp {
                m1_decl
            } else {
                unused_ok(&m1_decl)
            },
            slope = if q.log_interp {
                ", D = G(i) - G(i+1)"
            } else {
                " at segment middles"
            },
            lw1 = lf + ls,
            lmax = (1u32 << li) - 1,
        );
        // Stage 3.
        let body = if q.log_interp {
            let mut b = format!(
                "    wire [{lf}:0] g_tab = log2w[{}:{ls}];\n    wire [{}:0] d_tab = log2w[{}:0];\n",
                lf + ls,
                ls - 1,
                ls - 1
            );
            b += &product("dr", "d_tab", ls, "r2", low);
            b += &requantize(
                "dr_round",
                lf + 1,
                "dr",
                ls + low,
                low,
                0,
                Rounding::Nearest,
            );
            b += &format!("    wire [{lf}:0] g3 = g_tab - dr_round;\n");
            unused_ok(&b)
        } else {
            format!("    wire [{lf}:0] g3 = log2w;\n")
        };
        let _ = write!(
            s,
            "    // Stage 3: g{interp}, L = e - 1 + g = -log2(x), UQ4.{lf}.\n{body}\
    /* verilator lint_off UNUSEDSIGNAL */\n\
    wire [{lw}:0] l_sum = {{1'b0, e2, {lf}'b0}} + {{4'b0, g3}} - {lw2}'d{one};\n\
    /* verilator lint_on UNUSEDSIGNAL */\n\
    reg [{lw1}:0] l3;\n\
    reg zero3, one3;\n\
    reg [{n1}:0] n3;\n\
    always @(posedge clk) begin\n\
        l3 <= l_sum[{lw1}:0];\n\
        zero3 <= zero2;\n\
        one3 <= one2;\n\
        n3 <= n2;\n\
    end\n\n",
            interp = if q.log_interp {
                format!(" = G - round(D r / 2^{low})")
            } else {
                " = G".to_string()
            },
            lw1 = lw - 1,
            lw2 = lw + 1,
            one = 1u64 << lf,
            n1 = p.n_bits - 1,
        );
        // Stage 4.
        let _ = write!(
            s,
            "    // Stage 4: y = n L, UQ{}.{lf}.\n{}\
    /* verilator lint_off UNUSEDSIGNAL */\n\
    reg [{}:0] y4;\n\
    /* verilator lint_on UNUSEDSIGNAL */\n\
    reg zero4, one4;\n\
    always @(posedge clk) begin\n\
        y4 <= y_next;\n\
        zero4 <= zero3;\n\
        one4 <= one3;\n\
    end\n\n",
            yw - lf,
            product("y_next", "n3", p.n_bits, "l3", lw),
            yw - 1,
        );
        // Stage 5.
        let (w5_decl, w5_load) = if q.exp_interp {
            (
                format!("    reg [{}:0] w5;\n", wbits - 1),
                format!("        w5 <= y4[{}:0];\n", wbits - 1),
            )
        } else {
            (String::new(), String::new())
        };
        let _ = write!(
            s,
            "    // Stage 5: exp table (synchronous read) at y[{lf1}:{wbits}]: word = {{E, DE}},\n\
    // E = 2^(-u) UQ1.{ef}; k = floor(y); lobe 0 if k >= {kmax}.\n\
    reg [{ew1}:0] exp_rom [0:{emax}];\n\
    initial $readmemh(\"{m}_exp.hex\", exp_rom);\n\
    reg [{ew1}:0] exp5w;\n\
{w5_decl}\
    reg [3:0] k5;\n\
    reg zero5, one5;\n\
    always @(posedge clk) begin\n\
        exp5w <= exp_rom[y4[{lf1}:{wbits}]];\n\
{w5_load}\
        k5 <= y4[{k3}:{lf}];\n\
        zero5 <= zero4 | (|y4[{yw1}:{k4}]);\n\
        one5 <= one4;\n\
    end\n\n",
            lf1 = lf - 1,
            kmax = 1u32 << EXP_SHIFT_BITS,
            ew1 = ef + es,
            emax = (1u32 << ei) - 1,
            k3 = lf + EXP_SHIFT_BITS - 1,
            k4 = lf + EXP_SHIFT_BITS,
            yw1 = yw - 1,
        );
        // Stage 6.
        let body = if q.exp_interp {
            let mut b = format!(
                "    wire [{ef}:0] e_tab = exp5w[{}:{es}];\n    wire [{}:0] de_tab = exp5w[{}:0];\n",
                ef + es,
                es - 1,
                es - 1
            );
            b += &product("dw", "de_tab", es, "w5", wbits);
            b += &requantize(
                "dw_round",
                ef + 1,
                "dw",
                es + wbits,
                wbits,
                0,
                Rounding::Nearest,
            );
            b += &format!("    wire [{ef}:0] e6 = e_tab - dw_round;\n");
            unused_ok(&b)
        } else {
            format!("    wire [{ef}:0] e6 = exp5w;\n")
        };
        let _ = write!(
            s,
            "    // Stage 6: 2^(-u), shifted right by k; 1 if n = 0, 0 if x = 0 or y >= {kmax}.\n\
    // UQ1.{ef}.\n{body}\
    reg [{ef}:0] lobe6;\n\
    always @(posedge clk)\n\
        lobe6 <= one5 ? {ew}'d{one} : (zero5 ? {ew}'d0 : (e6 >> k5));\n\n",
            kmax = 1u32 << EXP_SHIFT_BITS,
            ew = ef + 1,
            one = 1u64 << ef,
        );
        s += &rgb_stage("lobe6", ef, LATENCY - 1, p, Rounding::Nearest);
        s += "endmodule\n\n`default_nettype wire\n";
        s
    }
}

impl HdlUnit for PowerUnit {
    fn module(&self) -> &'static str {
        Self::MODULE
    }

    fn describe(&self) -> String {
        let q = self.params;
        format!(
            "exact cos^n (log2 {}{} / exp2 {}{} tables, multiplier)",
            1u32 << q.log_index,
            if q.log_interp { " interp." } else { "" },
            1u32 << q.exp_index,
            if q.exp_interp { " interp." } else { "" }
        )
    }

    fn ports(&self) -> Ports {
        self.ports
    }

    fn latency(&self) -> u32 {
        LATENCY
    }

    fn eval(&self, input: &Input) -> Output {
        let lobe = self.lobe_code(input.cos, input.n);
        Output {
            rgb: input.ks.map(|k| {
                rq(
                    u128::from(lobe) * u128::from(k),
                    self.params.exp_frac,
                    0,
                    Rounding::Nearest,
                ) as u64
            }),
        }
    }

    fn rom_bits(&self) -> u64 {
        let q = self.params;
        (self.log.len() as u64) * u64::from(q.log_frac + 1 + self.log_slope_bits)
            + (self.exp.len() as u64) * u64::from(q.exp_frac + 1 + self.exp_slope_bits)
    }

    fn files(&self) -> Vec<HdlFile> {
        vec![
            HdlFile {
                name: format!("{}.v", Self::MODULE),
                text: self.module_text(),
            },
            HdlFile {
                name: format!("{}_log.hex", Self::MODULE),
                text: self.hex(
                    &self.log,
                    self.params.log_frac + 1,
                    self.log_slope_bits,
                    "g(m) = 1 - log2(1 + m), UQ1.log_frac",
                ),
            },
            HdlFile {
                name: format!("{}_exp.hex", Self::MODULE),
                text: self.hex(
                    &self.exp,
                    self.params.exp_frac + 1,
                    self.exp_slope_bits,
                    "2^(-u), UQ1.exp_frac",
                ),
            },
        ]
    }
}
