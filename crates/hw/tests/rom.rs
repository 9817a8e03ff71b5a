//! ROM1 contents, checked against hand-computed words, and the $readmemh text.

use glint_hw::{Coefficients, Rom, Rounding};

#[test]
fn energy_fit_words_by_hand() {
    // v = 4, n <= 1023, 16-bit words: a <= 1024/17 ≈ 60.2 needs 6 integer bits → UQ6.10.
    let rom = Rom::new(Coefficients::EnergyFit, 4, 10, 16, Rounding::Nearest).unwrap();
    assert_eq!((rom.int_bits(), rom.frac_bits()), (6, 10));
    let w = rom.words();
    assert_eq!(w.len(), 1024);
    assert_eq!(w[16], 1024); // a = 17/17 = 1.0
    assert_eq!(w[0], 60); // 1024/17 = 60.235... → 60
    assert_eq!(w[1], 120); // 2048/17 = 120.47 → 120
    assert_eq!(w[8], 542); // 9·1024/17 = 542.12 → 542
    assert_eq!(w[1023], 61681); // 1024·1024/17 = 61680.94 → 61681
    let t = Rom::new(Coefficients::EnergyFit, 4, 10, 16, Rounding::Truncate).unwrap();
    assert_eq!(t.words()[1023], 61680);
    assert_eq!(t.words()[1], 120);
    // v = 0: a = (n+1)/2 <= 512, 10 integer bits; a word of 10 bits is integers only.
    let r0 = Rom::new(Coefficients::EnergyFit, 0, 10, 10, Rounding::Nearest).unwrap();
    assert_eq!((r0.int_bits(), r0.frac_bits()), (10, 0));
    assert_eq!(r0.words()[0], 1); // 0.5 ties up
    assert_eq!(r0.words()[1023], 512);
}

#[test]
fn readmemh_text() {
    let rom = Rom::new(Coefficients::EnergyFit, 4, 10, 16, Rounding::Nearest).unwrap();
    let text = rom.to_readmemh();
    let data: Vec<&str> = text.lines().filter(|l| !l.starts_with("//")).collect();
    assert_eq!(data.len(), 1024);
    assert!(data
        .iter()
        .all(|l| l.len() == 4 && l.chars().all(|c| c.is_ascii_hexdigit())));
    assert_eq!(data[16], "0400");
    assert_eq!(data[1023], "f0f1");
    assert!(text.lines().next().unwrap().starts_with("// glint ROM1"));
    // 18-bit words take 5 hex digits.
    let wide = Rom::new(Coefficients::EnergyFit, 4, 10, 18, Rounding::Nearest).unwrap();
    let first = wide
        .to_readmemh()
        .lines()
        .find(|l| !l.starts_with("//"))
        .unwrap()
        .to_string();
    assert_eq!(first.len(), 5);
}

#[test]
fn minimax_words_fit_the_same_hardware() {
    // A small ROM (32 words) keeps the minimax search short in a debug build.
    let mm = Rom::new(Coefficients::Minimax, 4, 5, 16, Rounding::Nearest).unwrap();
    let k = Rom::new(Coefficients::EnergyFit, 4, 5, 16, Rounding::Nearest).unwrap();
    assert_eq!(mm.words().len(), 32);
    // n = 16 = 2^v: a = 1 reproduces cos^16 exactly, so minimax picks 1.0 too.
    let one = 1u64 << mm.frac_bits();
    assert!(mm.words()[16].abs_diff(one) <= 1, "{}", mm.words()[16]);
    // n = 0: cos^0 = 1 on [0, 1], matched exactly by a = 0.
    assert_eq!(mm.words()[0], 0);
    // Each word is its real coefficient, rounded.
    for (n, (&w, &a)) in mm.words().iter().zip(mm.exact()).enumerate() {
        let want = (a * 2f64.powi(mm.frac_bits() as i32)).round() as u64;
        assert!(w.abs_diff(want) <= 1, "n = {n}: {w} vs {want}");
    }
    // Minimax and energy fit agree where they should: both near n/2^v for large n.
    let (a_mm, a_k) = (mm.exact()[31], k.exact()[31]);
    assert!((a_mm - a_k).abs() / a_k < 0.1, "{a_mm} {a_k}");
}

#[test]
fn bad_rom_parameters() {
    assert!(Rom::new(Coefficients::EnergyFit, 11, 10, 16, Rounding::Nearest).is_err());
    assert!(Rom::new(Coefficients::EnergyFit, 4, 0, 16, Rounding::Nearest).is_err());
    assert!(Rom::new(Coefficients::EnergyFit, 4, 10, 0, Rounding::Nearest).is_err());
    assert!(Rom::new(Coefficients::EnergyFit, 4, 10, 65, Rounding::Nearest).is_err());
    assert!(Rom::new(Coefficients::EnergyFit, 4, 10, 5, Rounding::Nearest).is_err());
}
