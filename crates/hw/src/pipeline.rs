//! The cycle-accurate model: pipeline registers, one clock edge per [`Pipeline::clock`].
//!
//! Register stages (one clock each), in the order a Verilog emitter would write them:
//!
//! | stage | registers after the edge | combinational logic before it |
//! |---|---|---|
//! | 0 | RG1 `cos`, RG2 `n`, RG3..RG5 `ks` | (inputs) |
//! | 1 | `a` (ROM1, synchronous read), `t` | ROM1 read at address `n`; Sm1 `t = max(0, 1 - cos)` |
//! | 2 | `p` | MUL `p = round(a·t)` |
//! | 3 | `b` | Sm2 `d = 1 - p` (signed), SW `b = d < 0 ? 0 : d` |
//! | 3+k, k = 1..=v | `s_k` | BMUL stage k: `s_k = round(s_{k-1}^2)`, `s_0 = b` |
//! | v+4 | R, G, B outputs | MUL1..MUL3 `round(s_v · ks)` |
//!
//! The `ks` codes travel down the pipeline in delay registers beside the datapath, so
//! each result leaves with its own colour. Every register has a valid bit (here the
//! `Option`). Latency is `v + 4` clocks; one input is accepted per clock.

use crate::fixed::requantize;
use crate::{HwError, Input, Output, Unit};

/// Stage 1 register: ROM1 output and Sm1 output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RomSm1Reg {
    /// ROM1 word `a(n)`, UQ`coef_int`.`coef_frac`.
    pub a: u64,
    /// Sm1 output `t = max(0, 1 - cos)`, UQ2.`cos_frac`.
    pub t: u64,
    /// Delayed `k_s·I` codes.
    pub ks: [u64; 3],
}

/// Stage 2 register: the rounded MUL product.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MulReg {
    /// `p = round(a·t)`, UQ(`coef_int + 2`).`mul_frac`.
    pub p: u64,
    /// Delayed `k_s·I` codes.
    pub ks: [u64; 3],
}

/// Stage 3 register: the base after Sm2 and SW.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BaseReg {
    /// Sm2's signed output `1 - p` (a wire in hardware, kept here for traces).
    pub diff: i64,
    /// SW output `max(0, 1 - p)`, UQ1.`mul_frac`.
    pub b: u64,
    /// Delayed `k_s·I` codes.
    pub ks: [u64; 3],
}

/// A BMUL stage register.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SquareReg {
    /// `s_k = round(s_{k-1}^2)`, UQ1.`square_frac[k-1]`.
    pub s: u64,
    /// Delayed `k_s·I` codes.
    pub ks: [u64; 3],
}

/// Every pipeline register after the last clock edge; `None` is a register whose valid
/// bit is low.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Registers {
    /// Stage 0: RG1, RG2, RG3..RG5.
    pub input: Option<Input>,
    /// Stage 1: ROM1 and Sm1.
    pub rom_sm1: Option<RomSm1Reg>,
    /// Stage 2: MUL.
    pub mul: Option<MulReg>,
    /// Stage 3: Sm2 and SW.
    pub base: Option<BaseReg>,
    /// Stages 4 ..= 3+v: BMUL squarings.
    pub squares: Vec<Option<SquareReg>>,
    /// Stage v+4: the R, G, B output registers.
    pub output: Option<Output>,
}

/// The cycle-accurate pipeline of a [`Unit`].
#[derive(Clone, Debug)]
pub struct Pipeline<'u> {
    unit: &'u Unit,
    regs: Registers,
    cycle: u64,
}

impl<'u> Pipeline<'u> {
    /// A pipeline with every valid bit low (after reset).
    pub fn new(unit: &'u Unit) -> Pipeline<'u> {
        Pipeline {
            unit,
            regs: Registers {
                input: None,
                rom_sm1: None,
                mul: None,
                base: None,
                squares: vec![None; unit.config().v as usize],
                output: None,
            },
            cycle: 0,
        }
    }

    /// The registers after the last edge.
    pub fn registers(&self) -> &Registers {
        &self.regs
    }

    /// Clock edges so far.
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// One rising clock edge: every register loads its stage's result from the
    /// registers before the edge, and the input registers load `input` (`None` = valid
    /// low, a bubble). Returns the output registers after the edge: the result of the
    /// input given `latency()` calls earlier.
    ///
    /// An input that does not fit its registers is an error, and the pipeline is left
    /// unchanged (no edge).
    pub fn clock(&mut self, input: Option<Input>) -> Result<Option<Output>, HwError> {
        if let Some(inp) = &input {
            self.unit.check_input(inp)?;
        }
        let unit = self.unit;
        let f = unit.formats();
        let cfg = unit.config();
        let old = &self.regs;

        // Stage v+4: RGB multipliers.
        let lobe = match cfg.v {
            0 => old.base.map(|r| (r.b, f.mul_frac, r.ks)),
            v => old.squares[v as usize - 1].map(|r| (r.s, f.square_frac[v as usize - 1], r.ks)),
        };
        let output = lobe.map(|(s, frac, ks)| Output {
            rgb: ks.map(|k| requantize(s as u128 * k as u128, frac, 0, cfg.out_round) as u64),
        });

        // BMUL stages, each from the one before (stage 1 from the base register).
        let mut squares = Vec::with_capacity(old.squares.len());
        for k in 0..old.squares.len() {
            let (prev, prev_frac) = if k == 0 {
                (old.base.map(|r| (r.b, r.ks)), f.mul_frac)
            } else {
                (
                    old.squares[k - 1].map(|r| (r.s, r.ks)),
                    f.square_frac[k - 1],
                )
            };
            squares.push(prev.map(|(s, ks)| SquareReg {
                s: unit.square_stage(k, s, prev_frac),
                ks,
            }));
        }

        // Sm2 (signed subtractor) and SW (switch: zero where negative).
        let base = old.mul.map(|r| {
            let one = 1i128 << f.mul_frac;
            let diff = one - r.p as i128;
            BaseReg {
                diff: diff as i64,
                b: if diff < 0 { 0 } else { diff as u64 },
                ks: r.ks,
            }
        });

        // MUL: full product, rounded to mul_frac.
        let mul = old.rom_sm1.map(|r| MulReg {
            p: requantize(
                r.a as u128 * r.t as u128,
                f.coef_frac + f.t_frac,
                f.mul_frac,
                cfg.mul_round,
            ) as u64,
            ks: r.ks,
        });

        // ROM1 (synchronous read) and Sm1 (1 - cos, saturated at 0).
        let rom_sm1 = old.input.map(|r| {
            let one = 1i128 << f.cos_frac;
            let t = one - r.cos as i128;
            RomSm1Reg {
                a: unit.rom().words()[r.n as usize],
                t: if t < 0 { 0 } else { t as u64 },
                ks: r.ks,
            }
        });

        self.regs = Registers {
            input,
            rom_sm1,
            mul,
            base,
            squares,
            output,
        };
        self.cycle += 1;
        Ok(self.regs.output)
    }
}

/// The value of every stage for one input, read from the pipeline registers as the
/// input travels through them (for people reading the design).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Trace {
    /// The input registers.
    pub input: Input,
    /// Stage 1.
    pub rom_sm1: RomSm1Reg,
    /// Stage 2.
    pub mul: MulReg,
    /// Stage 3.
    pub base: BaseReg,
    /// Stages 4 ..= 3+v.
    pub squares: Vec<SquareReg>,
    /// The output registers.
    pub output: Output,
    /// Clock edges from loading the input to loading the output.
    pub latency: u32,
}

impl Unit {
    /// Runs `input` alone through a fresh [`Pipeline`] and records each stage's
    /// register as the input passes it.
    pub fn trace(&self, input: &Input) -> Result<Trace, HwError> {
        let mut pipe = Pipeline::new(self);
        pipe.clock(Some(*input))?;
        let mut rom_sm1 = None;
        let mut mul = None;
        let mut base = None;
        let mut squares = Vec::new();
        let mut edges = 0u32;
        let output = loop {
            let out = pipe.clock(None)?;
            edges += 1;
            let r = pipe.registers();
            rom_sm1 = rom_sm1.or(r.rom_sm1);
            mul = mul.or(r.mul);
            base = base.or(r.base);
            if let Some(sq) = r.squares.get(squares.len()).copied().flatten() {
                squares.push(sq);
            }
            if let Some(out) = out {
                break out;
            }
            if edges > self.latency() {
                unreachable!("a valid input always reaches the output after latency() edges");
            }
        };
        match (rom_sm1, mul, base) {
            (Some(rom_sm1), Some(mul), Some(base)) => Ok(Trace {
                input: *input,
                rom_sm1,
                mul,
                base,
                squares,
                output,
                latency: edges,
            }),
            _ => unreachable!("every stage holds the input once on its way out"),
        }
    }
}
