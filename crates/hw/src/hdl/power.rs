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

use std::fmt::Write as _;

use super::vlog::{header, product, requantize, rgb_stage, unused_ok, valid_and_ks};
use super::{HdlFile, HdlUnit, Ports};
use crate::fixed::requantize as rq;
use crate::{HwError, Input, Output, Rounding};

/// Fraction bits of the `cos` input this unit is designed for (Q1.14).
const COS_FRAC: u32 = 14;
/// Address bits of the log table (512 segments of the mantissa).
const LOG_INDEX: u32 = 9;
/// Fraction bits of `g` and `L` (UQ4.20): the log error is ~2^-21, which `n <= 1023`
/// amplifies to ~1e-3 relative at `cos` near 1, 0.2 LSB at 8 bits.
const LOG_FRAC: u32 = 20;
/// Width of the log table's slope field (`D <= 2^20·log2(1 + 1/512) = 2952`).
const LOG_SLOPE_BITS: u32 = 12;
/// Address bits of the exp table (256 segments of the fraction of `y`).
const EXP_INDEX: u32 = 8;
/// Fraction bits of the exp table and of the lobe (UQ1.16).
const EXP_FRAC: u32 = 16;
/// Width of the exp table's slope field (`DE <= 2^16·(1 - 2^(-1/256)) = 177.2`).
const EXP_SLOPE_BITS: u32 = 8;
/// `y = n·L >= 2^EXP_SHIFT_BITS` means `cos^n < 2^-16`: the lobe is 0. Shifts of up
/// to 15 are applied.
const EXP_SHIFT_BITS: u32 = 4;
/// Clocks from the input registers to the output registers (stages 1..=7).
const LATENCY: u32 = 7;

/// The log/exp `cos^n` unit (see the module documentation).
#[derive(Clone, Debug)]
pub struct PowerUnit {
    ports: Ports,
    log: Vec<(u64, u64)>,
    exp: Vec<(u64, u64)>,
}

impl PowerUnit {
    /// Module name, and stem of the file names.
    pub const MODULE: &'static str = "glint_pow";

    /// The unit for `ports`; the tables are designed for a Q1.14 `cos` (16 bits), so
    /// other widths are refused. `n_bits <= 10` and `out_bits <= 10` keep the error
    /// within 1 LSB.
    pub fn new(ports: Ports) -> Result<PowerUnit, HwError> {
        if ports.cos_bits != COS_FRAC + 2 || ports.n_bits > 10 || ports.out_bits > 10 {
            return Err(HwError::Unsupported(format!(
                "the cos^n unit is designed for cos_bits = 16, n_bits <= 10, out_bits <= 10 (got {}, {}, {})",
                ports.cos_bits, ports.n_bits, ports.out_bits
            )));
        }
        let table = |count: u32, frac: u32, f: &dyn Fn(f64) -> f64| -> Vec<(u64, u64)> {
            let q = |i: u32| {
                (f(f64::from(i) / f64::from(count)) * 2f64.powi(frac as i32)).round() as u64
            };
            (0..count).map(|i| (q(i), q(i) - q(i + 1))).collect()
        };
        Ok(PowerUnit {
            ports,
            log: table(1 << LOG_INDEX, LOG_FRAC, &|m| 1.0 - (1.0 + m).log2()),
            exp: table(1 << EXP_INDEX, EXP_FRAC, &|u| (-u).exp2()),
        })
    }

    /// The lobe code, UQ1.16: the datapath of stages 1..=6.
    pub fn lobe_code(&self, cos: i64, n: u32) -> u64 {
        let one = 1i64 << COS_FRAC;
        let x = cos.clamp(0, one) as u64;
        if n == 0 {
            return 1 << EXP_FRAC;
        }
        if x == 0 {
            return 0;
        }
        // Stage 1: x = 2^(14-e) (1 + m), leading one moved to bit 14.
        let e = u64::from(x.leading_zeros()) - (63 - u64::from(COS_FRAC));
        let m = (x << e) & ((1 << COS_FRAC) - 1);
        // Stages 2-3: g = 1 - log2(1 + m), L = e - 1 + g = -log2(x).
        let low = COS_FRAC - LOG_INDEX;
        let (g0, d) = self.log[(m >> low) as usize];
        let r = m & ((1 << low) - 1);
        let g = g0 - rq(u128::from(d * r), low, 0, Rounding::Nearest) as u64;
        let l = (e << LOG_FRAC) + g - (1 << LOG_FRAC);
        // Stage 4: y = n L.
        let y = u64::from(n) * l;
        // Stages 5-6.
        let k = y >> LOG_FRAC;
        if k >= 1 << EXP_SHIFT_BITS {
            return 0;
        }
        let u = y & ((1 << LOG_FRAC) - 1);
        let wbits = LOG_FRAC - EXP_INDEX;
        let (e0, de) = self.exp[(u >> wbits) as usize];
        let w = u & ((1 << wbits) - 1);
        let ev = e0 - rq(u128::from(de * w), wbits, 0, Rounding::Nearest) as u64;
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

    fn module_text(&self) -> String {
        let p = self.ports;
        let m = Self::MODULE;
        let (lf, li, ls) = (LOG_FRAC, LOG_INDEX, LOG_SLOPE_BITS);
        let (ef, ei, es) = (EXP_FRAC, EXP_INDEX, EXP_SLOPE_BITS);
        let low = COS_FRAC - LOG_INDEX;
        let wbits = LOG_FRAC - EXP_INDEX;
        let lw = lf + 4; // L: UQ4.20
        let yw = lw + p.n_bits; // y: UQ(4+n_bits).20
        let mut s = format!(
            "// {m}: an exact cos^n specular unit for comparison (log2 table, multiplier, exp2\n\
// table, each table linearly interpolated), generated by glint-hw. Verilog-2005.\n\
//   cos^n = 2^(-n L),  L = -log2(cos);  R, G, B = round(cos^n * k_s*I)\n\
// Latency {LATENCY} clocks, one input per clock. cos is clamped to [0, 1]; n = 0 gives 1.\n"
        );
        s += &header(m, p);
        s += &valid_and_ks(LATENCY, p);
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
    reg [13:0] m1;\n\
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
    // G = 1 - log2(1 + i/{count}) UQ1.{lf}, D = G(i) - G(i+1).\n\
    reg [{lw1}:0] log_rom [0:{lmax}];\n\
    initial $readmemh(\"{m}_log.hex\", log_rom);\n\
    reg [{lw1}:0] log2w;\n\
    reg [{low1}:0] r2;\n\
    reg [3:0] e2;\n\
    reg zero2, one2;\n\
    reg [{n1}:0] n2;\n\
    always @(posedge clk) begin\n\
        log2w <= log_rom[m1[13:{low}]];\n\
        r2 <= m1[{low1}:0];\n\
        e2 <= e1;\n\
        zero2 <= zero1;\n\
        one2 <= one1;\n\
        n2 <= n1;\n\
    end\n\n",
            n1 = p.n_bits - 1,
            nb = p.n_bits,
            count = 1u32 << li,
            lw1 = lf + 1 + ls - 1,
            lmax = (1u32 << li) - 1,
            low1 = low - 1,
        );
        // Stage 3.
        let mut body = format!(
            "    wire [{}:0] g_tab = log2w[{}:{ls}];\n    wire [{}:0] d_tab = log2w[{}:0];\n",
            lf,
            lf + ls,
            ls - 1,
            ls - 1
        );
        body += &product("dr", "d_tab", ls, "r2", low);
        body += &requantize(
            "dr_round",
            lf + 1,
            "dr",
            ls + low,
            low,
            0,
            Rounding::Nearest,
        );
        let _ = write!(
            s,
            "    // Stage 3: g = G - round(D r / 2^{low}), L = e - 1 + g = -log2(x), UQ4.{lf}.\n{}\
    wire [{lf}:0] g3 = g_tab - dr_round;\n\
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
            unused_ok(&body),
            lw1 = lw - 1,
            lw2 = lw + 1,
            one = 1u64 << lf,
            n1 = p.n_bits - 1,
        );
        // Stage 4.
        let _ = write!(
            s,
            "    // Stage 4: y = n L, UQ{}.{lf}.\n{}\
    reg [{}:0] y4;\n\
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
        let _ = write!(
            s,
            "    // Stage 5: exp table (synchronous read) at y[{lf1}:{wbits}]: word = {{E, DE}},\n\
    // E = 2^(-j/{ecount}) UQ1.{ef}, DE = E(j) - E(j+1); k = floor(y); lobe 0 if k >= {kmax}.\n\
    reg [{ew1}:0] exp_rom [0:{emax}];\n\
    initial $readmemh(\"{m}_exp.hex\", exp_rom);\n\
    reg [{ew1}:0] exp5w;\n\
    reg [{wb1}:0] w5;\n\
    reg [3:0] k5;\n\
    reg zero5, one5;\n\
    always @(posedge clk) begin\n\
        exp5w <= exp_rom[y4[{lf1}:{wbits}]];\n\
        w5 <= y4[{wb1}:0];\n\
        k5 <= y4[{k3}:{lf}];\n\
        zero5 <= zero4 | (|y4[{yw1}:{k4}]);\n\
        one5 <= one4;\n\
    end\n\n",
            lf1 = lf - 1,
            ecount = 1u32 << ei,
            kmax = 1u32 << EXP_SHIFT_BITS,
            ew1 = ef + 1 + es - 1,
            emax = (1u32 << ei) - 1,
            wb1 = wbits - 1,
            k3 = lf + EXP_SHIFT_BITS - 1,
            k4 = lf + EXP_SHIFT_BITS,
            yw1 = yw - 1,
        );
        // Stage 6.
        let mut body = format!(
            "    wire [{ef}:0] e_tab = exp5w[{}:{es}];\n    wire [{}:0] de_tab = exp5w[{}:0];\n",
            ef + es,
            es - 1,
            es - 1
        );
        body += &product("dw", "de_tab", es, "w5", wbits);
        body += &requantize(
            "dw_round",
            ef + 1,
            "dw",
            es + wbits,
            wbits,
            0,
            Rounding::Nearest,
        );
        let _ = write!(
            s,
            "    // Stage 6: 2^(-u) = E - round(DE w / 2^{wbits}), shifted right by k; 1 if n = 0,\n\
    // 0 if x = 0 or y >= {kmax}. UQ1.{ef}.\n{}\
    wire [{ef}:0] e6 = e_tab - dw_round;\n\
    reg [{ef}:0] lobe6;\n\
    always @(posedge clk)\n\
        lobe6 <= one5 ? {ew}'d{one} : (zero5 ? {ew}'d0 : (e6 >> k5));\n\n",
            unused_ok(&body),
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
        "exact cos^n (log2/exp2 tables, multiplier)".into()
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
                    EXP_FRAC,
                    0,
                    Rounding::Nearest,
                ) as u64
            }),
        }
    }

    fn rom_bits(&self) -> u64 {
        (self.log.len() as u64) * u64::from(LOG_FRAC + 1 + LOG_SLOPE_BITS)
            + (self.exp.len() as u64) * u64::from(EXP_FRAC + 1 + EXP_SLOPE_BITS)
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
                    LOG_FRAC + 1,
                    LOG_SLOPE_BITS,
                    "g(m) = 1 - log2(1 + m), m = i/512, UQ1.20",
                ),
            },
            HdlFile {
                name: format!("{}_exp.hex", Self::MODULE),
                text: self.hex(
                    &self.exp,
                    EXP_FRAC + 1,
                    EXP_SLOPE_BITS,
                    "2^(-u), u = j/256, UQ1.16",
                ),
            },
        ]
    }
}
