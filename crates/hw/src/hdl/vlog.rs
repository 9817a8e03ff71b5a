//! Small helpers that write Verilog-2005 text: rounded products and the shared ports.

use std::fmt::Write as _;

use super::Ports;
use crate::Rounding;

/// `wire [W-1:0] name = a * b;` with both operands zero-extended to the product's
/// full width `W = aw + bw` (so Verilator sees no implicit width change).
pub(crate) fn product(name: &str, a: &str, aw: u32, b: &str, bw: u32) -> String {
    let w = aw + bw;
    format!(
        "    wire [{}:0] {name} = {{{{{bw}{{1'b0}}}}, {a}}} * {{{{{aw}{{1'b0}}}}, {b}}};\n",
        w - 1
    )
}

/// Declares `wire [out_w-1:0] out` holding `src` (`src_w` bits, `from` fraction bits)
/// re-expressed with `to` fraction bits, exactly as [`crate::requantize`]: a left shift
/// when `to >= from`, else the low `from - to` bits dropped (`truncate`) or dropped
/// with the highest dropped bit added (`nearest`, ties up). The caller guarantees the
/// value fits `out_w` bits; the wider intermediate and the dropped bits are unused, so
/// the block sits in a Verilator `UNUSEDSIGNAL` exemption.
pub(crate) fn requantize(
    out: &str,
    out_w: u32,
    src: &str,
    src_w: u32,
    from: u32,
    to: u32,
    mode: Rounding,
) -> String {
    let (expr, w) = if to >= from {
        let sh = to - from;
        if sh == 0 {
            (src.to_string(), src_w)
        } else {
            (format!("{{{src}, {sh}'b0}}"), src_w + sh)
        }
    } else {
        let k = from - to;
        assert!(k < src_w, "requantize drops every bit of {src}");
        let hi = format!("{src}[{}:{k}]", src_w - 1);
        match mode {
            Rounding::Truncate => (hi, src_w - k),
            Rounding::Nearest => {
                let w = src_w - k + 1;
                (
                    format!(
                        "{{1'b0, {hi}}} + {{{{{}{{1'b0}}}}, {src}[{}]}}",
                        w - 1,
                        k - 1
                    ),
                    w,
                )
            }
        }
    };
    let mut s = String::new();
    let _ = writeln!(s, "    wire [{}:0] {out}_full = {expr};", w - 1);
    if out_w < w {
        let _ = writeln!(
            s,
            "    wire [{}:0] {out} = {out}_full[{}:0];",
            out_w - 1,
            out_w - 1
        );
    } else if out_w > w {
        let _ = writeln!(
            s,
            "    wire [{}:0] {out} = {{{}'b0, {out}_full}};",
            out_w - 1,
            out_w - w
        );
    } else {
        let _ = writeln!(s, "    wire [{}:0] {out} = {out}_full;", out_w - 1);
    }
    s
}

/// Wraps `body` in a Verilator exemption for unused bits (the dropped low bits of a
/// rounded product, and high bits that are zero by construction).
pub(crate) fn unused_ok(body: &str) -> String {
    format!(
        "    /* verilator lint_off UNUSEDSIGNAL */\n{body}    /* verilator lint_on UNUSEDSIGNAL */\n"
    )
}

/// The module header with the shared ports (see [`super`]).
pub(crate) fn header(module: &str, p: Ports) -> String {
    let ob = p.out_bits - 1;
    format!(
        "`default_nettype none\n\
module {module} (\n\
    input  wire        clk,\n\
    input  wire        rst,      // synchronous, active high: clears every valid bit\n\
    input  wire        in_valid,\n\
    input  wire [{c}:0] cos_in,   // cos(gamma), signed Q1.{f}\n\
    input  wire [{n}:0] n_in,     // shininess n, unsigned\n\
    input  wire [{ob}:0] ks_r_in,  // k_s*I per channel, unsigned, full scale {fs}\n\
    input  wire [{ob}:0] ks_g_in,\n\
    input  wire [{ob}:0] ks_b_in,\n\
    output reg         out_valid,\n\
    output reg  [{ob}:0] r_out,    // round(lobe * k_s*I)\n\
    output reg  [{ob}:0] g_out,\n\
    output reg  [{ob}:0] b_out\n\
);\n",
        c = p.cos_bits - 1,
        f = p.cos_bits - 2,
        n = p.n_bits - 1,
        fs = super::mask(p.out_bits),
    )
}

/// The valid shift register and the `k_s·I` delay line for a pipeline of `latency`
/// edges: `vld[k]` and `ks{k}` are stage `k`'s (stage 0 = the input registers), and
/// `out_valid` is loaded from the last stage. Also the stage-0 `ks0` load.
pub(crate) fn valid_and_ks(latency: u32, p: Ports) -> String {
    let kw = 3 * p.out_bits;
    let last = latency - 1;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "    // Valid bits: vld[k] is stage k's; a bubble in is a bubble out.\n\
    reg [{last}:0] vld;\n\
    always @(posedge clk) begin\n\
        if (rst) begin\n\
            vld <= {latency}'b0;\n\
            out_valid <= 1'b0;\n\
        end else begin\n\
            vld <= {{vld[{}:0], in_valid}};\n\
            out_valid <= vld[{last}];\n\
        end\n\
    end\n",
        last.saturating_sub(1),
    );
    if latency == 1 {
        s = s.replace("{vld[0:0], in_valid}", "in_valid");
    }
    let _ = writeln!(
        s,
        "    // k_s*I {{R, G, B}} travels beside the datapath: ks<k> is stage k's."
    );
    for k in 0..latency {
        let _ = writeln!(s, "    reg [{}:0] ks{k};", kw - 1);
    }
    let _ = writeln!(s, "    always @(posedge clk) begin");
    let _ = writeln!(s, "        ks0 <= {{ks_r_in, ks_g_in, ks_b_in}};");
    for k in 1..latency {
        let _ = writeln!(s, "        ks{k} <= ks{};", k - 1);
    }
    let _ = writeln!(s, "    end\n");
    s
}

/// The RGB multipliers: `round(lobe · ks)` per channel (lobe UQ1.`frac`), loaded into
/// the output registers from stage `stage`'s `ks` and `lobe`.
pub(crate) fn rgb_stage(lobe: &str, frac: u32, stage: u32, p: Ports, round: Rounding) -> String {
    let ob = p.out_bits;
    let lw = frac + 1;
    let mut body = String::new();
    for (i, ch) in ["r", "g", "b"].iter().enumerate() {
        let hi = ob * (3 - i as u32) - 1;
        let lo = ob * (2 - i as u32);
        body += &format!("    wire [{}:0] ks_{ch} = ks{stage}[{hi}:{lo}];\n", ob - 1);
        body += &product(&format!("prod_{ch}"), lobe, lw, &format!("ks_{ch}"), ob);
        body += &requantize(
            &format!("{ch}_next"),
            ob,
            &format!("prod_{ch}"),
            lw + ob,
            frac,
            0,
            round,
        );
    }
    format!(
        "    // RGB multipliers: round(lobe * k_s*I), U{ob} (lobe <= 1, so the result <= k_s*I).\n\
{}\
    always @(posedge clk) begin\n\
        r_out <= r_next;\n\
        g_out <= g_next;\n\
        b_out <= b_next;\n\
    end\n",
        unused_ok(&body)
    )
}
