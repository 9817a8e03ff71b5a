//! Verilog of the K_v design space's cheaper circuits: the symmetric (and truncated)
//! squarer array and the shift-and-add constant multiplier. Their models are in
//! `crate::arith`.

use std::fmt::Write as _;

/// `{k{1'b0}}`, or nothing for `k = 0` (Verilog-2005 forbids a zero replication).
fn zeros(k: u32) -> Option<String> {
    (k > 0).then(|| format!("{{{k}{{1'b0}}}}"))
}

/// A concatenation of the present parts.
fn concat(parts: &[Option<String>]) -> String {
    let p: Vec<&str> = parts.iter().flatten().map(String::as_str).collect();
    if p.len() == 1 {
        p[0].to_string()
    } else {
        format!("{{{}}}", p.join(", "))
    }
}

/// Declares `wire [2w-1:0] name` = `x^2` (`x` is `w` bits) from the symmetric array:
/// row `i` is `x_i · (2^(2i) + Σ_{j>i} x_j 2^(i+j+1))`, i.e. the bits
/// `{x[w-1:i+1], 0, x_i}` gated by `x_i`, at column `2i`. With `drop > 0` the columns
/// below `drop` are masked off and `comp` is added (see `crate::TruncatedSquare`).
pub(crate) fn square_array(name: &str, x: &str, w: u32, drop: u32, comp: u64) -> String {
    let pw = 2 * w;
    let mut s = String::new();
    let mut rows = Vec::new();
    for i in 0..w {
        let row = format!("{name}_r{i}");
        let bits = if i + 1 < w {
            let width = w - i + 1;
            format!(
                "({{{x}[{}:{}], 1'b0, {x}[{i}]}} & {{{width}{{{x}[{i}]}}}})",
                w - 1,
                i + 1
            )
        } else {
            format!("{x}[{i}]")
        };
        let width = if i + 1 < w { w - i + 1 } else { 1 };
        let mut expr = concat(&[zeros(pw - width - 2 * i), Some(bits), zeros(2 * i)]);
        if drop > 0 {
            // Each row loses its bits below column `drop` (masking the sum instead
            // would keep the carries out of the dropped columns).
            let mask: u128 = ((1u128 << pw) - 1) & !((1u128 << drop) - 1);
            expr = format!(
                "{expr} & {pw}'h{mask:0digits$x}",
                digits = pw.div_ceil(4) as usize
            );
        }
        let _ = writeln!(s, "    wire [{}:0] {row} = {expr};", pw - 1);
        rows.push(row);
    }
    let mut sum = rows.join(" + ");
    if drop > 0 {
        sum = format!("{sum} + {pw}'d{comp}");
        let _ = writeln!(
            s,
            "    // Truncated: partial-product columns below {drop} dropped, their mean {comp} added."
        );
    }
    let _ = writeln!(s, "    wire [{}:0] {name} = {sum};", pw - 1);
    s
}

/// Declares `wire [W-1:0] name` = `x · k` (`x` is `xw` bits) as a sum of shifted
/// copies of `x`, one per canonical signed digit of `k`, `W = xw + bits(k) + 1`
/// (modular arithmetic: the result is exact since `x·k < 2^W`). Returns the text and `W`.
pub(crate) fn const_multiply(
    name: &str,
    x: &str,
    xw: u32,
    k: u128,
    csd: &[(u32, i8)],
) -> (String, u32) {
    let kbits = 128 - k.leading_zeros();
    let w = xw + kbits + 1;
    let mut terms = String::new();
    // Positive digits first, so the expression reads as additions then subtractions.
    let mut digits: Vec<(u32, i8)> = csd.to_vec();
    digits.sort_by_key(|&(s, g)| (g < 0, s));
    for (idx, &(shift, sign)) in digits.iter().enumerate() {
        let term = concat(&[zeros(w - xw - shift), Some(x.to_string()), zeros(shift)]);
        match (idx, sign) {
            (0, _) => terms += &term,
            (_, g) if g > 0 => terms += &format!(" + {term}"),
            _ => terms += &format!(" - {term}"),
        }
    }
    if digits.is_empty() {
        terms = format!("{w}'d0");
    }
    let text = format!(
        "    // x * {k} as {} shifted additions/subtractions (canonical signed digits).\n    wire [{}:0] {name} = {terms};\n",
        digits.len(),
        w - 1
    );
    (text, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texts_have_the_right_shape() {
        let s = square_array("sq", "x", 3, 0, 0);
        assert!(
            s.contains("wire [5:0] sq_r0 = {{2{1'b0}}, ({x[2:1], 1'b0, x[0]} & {4{x[0]}})};"),
            "{s}"
        );
        assert!(
            s.contains("wire [5:0] sq_r2 = {{1{1'b0}}, x[2], {4{1'b0}}};"),
            "{s}"
        );
        let s = square_array("sq", "x", 3, 2, 1);
        assert!(s.contains("& 6'h3c;"), "{s}");
        assert!(s.contains(" + 6'd1;"), "{s}");
        let (t, w) = const_multiply("p", "n", 4, 15, &crate::csd_digits(15));
        assert_eq!(w, 9);
        assert!(t.contains("- {{5{1'b0}}, n}"), "{t}");
    }
}
