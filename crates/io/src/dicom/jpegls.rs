//! A JPEG-LS decoder (ITU-T T.87 / ISO/IEC 14495-1): lossless and near-lossless, 2 to
//! 16 bits, one to four components, interleave modes none, line and sample, preset
//! parameters (LSE id 1).
//!
//! Written here rather than taken from a crate: glint read JPEG-LS through CharLS
//! (`charls-sys`), which is C++ built with CMake, and the default build must need a Rust
//! toolchain and a C compiler only (issue 39). Of the pure-Rust decoders on crates.io,
//! `dicom-toolkit-codec` 0.5.0 failed on every JPEG-LS frame of pydicom's corpus (15 of
//! 15: "unexpected end of bitstream", "ILV_SAMPLE multi-component not yet implemented")
//! and `pure_jpegls` 2.0.0 decodes single-component scans only (pydicom's corpus has
//! line- and sample-interleaved colour). The decoder follows CharLS 2.4's choices where
//! T.87 leaves room (one set of regular contexts shared by the components of a scan, a
//! run index per component in line interleave, run-interruption context 0 for every
//! component of a sample-interleaved triplet) and writes its output layout (planar for
//! interleave mode none, pixel-interleaved otherwise; one byte a sample up to 8 bits, two
//! little-endian bytes above), so its samples equal CharLS's bit for bit
//! (`crates/io/tests/pydicom_corpus.rs` checks them against pydicom with CharLS).

/// Whether a transfer syntax is JPEG-LS (lossless .80 or near-lossless .81).
pub(super) fn is_jpeg_ls(ts: &str) -> bool {
    ts == "1.2.840.10008.1.2.4.80" || ts == "1.2.840.10008.1.2.4.81"
}

/// T.87 Table A.1 / CharLS: the run-length order J[RUNindex].
const J: [u32; 32] = [
    0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 9, 10, 11, 12, 13,
    14, 15,
];

/// The frame header (SOF55) and the preset parameters in force.
#[derive(Clone, Copy, Debug, Default)]
struct Frame {
    precision: u32,
    width: usize,
    height: usize,
    components: usize,
    /// LSE id 1 fields; 0 means the default.
    maxval: i32,
    t1: i32,
    t2: i32,
    t3: i32,
    reset: i32,
}

/// Coding parameters of one scan (T.87 C.2.4.1).
#[derive(Clone, Copy, Debug)]
struct Params {
    maxval: i32,
    near: i32,
    range: i32,
    qbpp: u32,
    limit: i32,
    t1: i32,
    t2: i32,
    t3: i32,
    reset: i32,
}

fn ceil_log2(x: i32) -> u32 {
    let mut k = 0;
    while (1i64 << k) < i64::from(x) {
        k += 1;
    }
    k
}

impl Params {
    fn new(f: &Frame, near: i32) -> Result<Self, String> {
        let maxval = if f.maxval > 0 {
            f.maxval
        } else {
            (1 << f.precision) - 1
        };
        if near < 0 || near > (maxval / 2).min(255) {
            return Err(format!("a JPEG-LS scan with NEAR {near}"));
        }
        let range = (maxval + 2 * near) / (2 * near + 1) + 1;
        let bpp = ceil_log2(maxval + 1).max(2) as i32;
        let (d1, d2, d3) = default_thresholds(maxval, near);
        let pick = |v: i32, d: i32| if v > 0 { v } else { d };
        let p = Self {
            maxval,
            near,
            range,
            qbpp: ceil_log2(range),
            limit: 2 * (bpp + bpp.max(8)),
            t1: pick(f.t1, d1),
            t2: pick(f.t2, d2),
            t3: pick(f.t3, d3),
            reset: pick(f.reset, 64),
        };
        if !(p.near < p.t1 && p.t1 <= p.t2 && p.t2 <= p.t3) || p.reset < 3 {
            return Err("JPEG-LS preset thresholds out of order".into());
        }
        Ok(p)
    }

    /// The gradient's quantised region (T.87 A.3.3).
    fn quantize(&self, d: i32) -> i32 {
        if d <= -self.t3 {
            -4
        } else if d <= -self.t2 {
            -3
        } else if d <= -self.t1 {
            -2
        } else if d < -self.near {
            -1
        } else if d <= self.near {
            0
        } else if d < self.t1 {
            1
        } else if d < self.t2 {
            2
        } else if d < self.t3 {
            3
        } else {
            4
        }
    }

    fn context(&self, a: i32, b: i32, c: i32, d: i32) -> i32 {
        (self.quantize(d - b) * 9 + self.quantize(b - c)) * 9 + self.quantize(c - a)
    }

    fn clamp(&self, x: i32) -> i32 {
        x.clamp(0, self.maxval)
    }

    /// Rx from Px and the error (T.87 A.4.4 and A.5.2: modulo reduction, clamping).
    fn reconstruct(&self, predicted: i32, error: i32) -> i32 {
        let m = 2 * self.near + 1;
        let mut v = predicted + error * m;
        if v < -self.near {
            v += self.range * m;
        } else if v > self.maxval + self.near {
            v -= self.range * m;
        }
        self.clamp(v)
    }
}

/// T.87 C.2.4.1.1: the default thresholds for MAXVAL and NEAR.
fn default_thresholds(maxval: i32, near: i32) -> (i32, i32, i32) {
    // BASIC_T1, BASIC_T2, BASIC_T3: the thresholds for MAXVAL 255, NEAR 0 (Table C.3).
    const BASIC: [i32; 3] = [3, 7, 21];
    let clamp = |i: i32, j: i32| if i > maxval || i < j { j } else { i };
    if maxval >= 128 {
        let f = (maxval.min(4095) + 128) / 256;
        let t1 = clamp(f * (BASIC[0] - 2) + 2 + 3 * near, near + 1);
        let t2 = clamp(f * (BASIC[1] - 3) + 3 + 5 * near, t1);
        (t1, t2, clamp(f * (BASIC[2] - 4) + 4 + 7 * near, t2))
    } else {
        let f = 256 / (maxval + 1);
        let t1 = clamp((BASIC[0] / f + 3 * near).max(2), near + 1);
        let t2 = clamp((BASIC[1] / f + 5 * near).max(3), t1);
        (t1, t2, clamp((BASIC[2] / f + 7 * near).max(4), t2))
    }
}

/// A regular-mode context (T.87 A.2.1).
#[derive(Clone, Copy)]
struct Regular {
    a: i32,
    b: i32,
    c: i32,
    n: i32,
}

/// A run-interruption context (T.87 A.7.2; index 365 and 366).
#[derive(Clone, Copy)]
struct Interruption {
    kind: i32,
    a: i32,
    n: i32,
    nn: i32,
}

/// Bits of one scan, with T.87's marker stuffing: after an FF byte the next byte's top
/// bit is a stuffed zero. Reads past the scan's end give zeros and are counted, so a
/// cut stream is an error at the end of the scan, not a panic or an endless loop.
struct Bits<'a> {
    data: &'a [u8],
    pos: usize,
    cache: u64,
    valid: u32,
    past_end: u32,
}

impl<'a> Bits<'a> {
    fn new(data: &'a [u8]) -> Self {
        Self {
            data,
            pos: 0,
            cache: 0,
            valid: 0,
            past_end: 0,
        }
    }

    fn fill(&mut self) {
        while self.valid <= 56 {
            let Some(&byte) = self.data.get(self.pos) else {
                self.valid += 8;
                self.past_end += 8;
                continue;
            };
            if byte == 0xFF && self.data.get(self.pos + 1).is_none_or(|&n| n >= 0x80) {
                // A marker ends the scan's data.
                self.data = &self.data[..self.pos];
                continue;
            }
            let after_ff = self.pos > 0 && self.data[self.pos - 1] == 0xFF;
            self.pos += 1;
            if after_ff {
                self.cache |= u64::from(byte & 0x7F) << (57 - self.valid);
                self.valid += 7;
            } else {
                self.cache |= u64::from(byte) << (56 - self.valid);
                self.valid += 8;
            }
        }
    }

    fn read(&mut self, n: u32) -> i32 {
        if n == 0 {
            return 0;
        }
        if self.valid < n {
            self.fill();
        }
        let v = (self.cache >> (64 - n)) as i32;
        self.cache <<= n;
        self.valid -= n;
        v
    }

    fn bit(&mut self) -> bool {
        self.read(1) == 1
    }

    /// The unary prefix: zeros before a one (bounded: a valid prefix is below LIMIT).
    fn zeros(&mut self, bound: i32) -> Result<i32, String> {
        let mut count = 0;
        while !self.bit() {
            count += 1;
            if count > bound {
                return Err("a JPEG-LS code longer than its limit".into());
            }
        }
        Ok(count)
    }

    /// The limited-length Golomb code of T.87 A.5.3.
    fn golomb(&mut self, k: u32, limit: i32, qbpp: u32) -> Result<i32, String> {
        let high = self.zeros(limit)?;
        if high >= limit - (qbpp as i32 + 1) {
            return Ok(self.read(qbpp) + 1);
        }
        if k == 0 {
            return Ok(high);
        }
        if k > 24 {
            return Err("a JPEG-LS Golomb parameter out of range".into());
        }
        Ok((high << k) + self.read(k))
    }

    fn check(&self) -> Result<(), String> {
        // CharLS reads zeros past the end while its cache held bits when it filled:
        // about one cache's worth. More is a cut stream.
        if self.past_end.saturating_sub(self.valid) > 64 {
            return Err("JPEG-LS scan data cut short".into());
        }
        Ok(())
    }
}

/// The state of one scan: its parameters, contexts and bits.
struct Scan<'a> {
    p: Params,
    regular: Vec<Regular>,
    interruption: [Interruption; 2],
    run_index: usize,
    bits: Bits<'a>,
}

impl<'a> Scan<'a> {
    fn new(p: Params, data: &'a [u8]) -> Self {
        let a = ((p.range + 32) / 64).max(2);
        let regular = Regular {
            a,
            b: 0,
            c: 0,
            n: 1,
        };
        let run = |kind| Interruption {
            kind,
            a,
            n: 1,
            nn: 0,
        };
        Self {
            p,
            regular: vec![regular; 365],
            interruption: [run(0), run(1)],
            run_index: 0,
            bits: Bits::new(data),
        }
    }

    /// Regular mode (T.87 A.4 to A.6) for a sample of context `qs` predicted `predicted`.
    fn regular(&mut self, qs: i32, predicted: i32) -> Result<i32, String> {
        let sign = if qs < 0 { -1 } else { 1 };
        let ctx = &mut self.regular[qs.unsigned_abs() as usize];
        let px = self.p.clamp(predicted + sign * ctx.c);
        let mut k = 0;
        while (ctx.n << k) < ctx.a && k < 16 {
            k += 1;
        }
        let mapped = self.bits.golomb(k, self.p.limit, self.p.qbpp)?;
        let mut error = if mapped & 1 == 1 {
            -((mapped + 1) >> 1)
        } else {
            mapped >> 1
        };
        if k == 0 && self.p.near == 0 && 2 * ctx.b + ctx.n - 1 < 0 {
            error = -(error + 1);
        }
        if error.abs() > 65535 {
            return Err("a JPEG-LS error value out of range".into());
        }
        update(ctx, error, self.p.near, self.p.reset);
        Ok(self.p.reconstruct(px, sign * error))
    }

    /// The run length of T.87 A.7.1.2, at most `left` samples; then whether the run
    /// reached the end of the line (no interruption sample follows).
    fn run(&mut self, left: usize) -> Result<(usize, bool), String> {
        let mut count = 0usize;
        while self.bits.bit() {
            let step = (1usize << J[self.run_index]).min(left - count);
            count += step;
            if step == 1 << J[self.run_index] {
                self.run_index = (self.run_index + 1).min(31);
            }
            if count == left {
                return Ok((count, true));
            }
        }
        count += self.bits.read(J[self.run_index]) as usize;
        if count > left {
            return Err("a JPEG-LS run past the end of its line".into());
        }
        // A remainder reaching the end of the line ends it without an interruption
        // sample, as CharLS decodes it.
        Ok((count, count == left))
    }

    /// The error of a run-interruption sample (T.87 A.7.2) in context 365 + `which`.
    fn interruption_error(&mut self, which: usize) -> Result<i32, String> {
        let limit = self.p.limit - J[self.run_index] as i32 - 1;
        let ctx = &mut self.interruption[which];
        let temp = ctx.a + (ctx.n >> 1) * ctx.kind;
        let (mut n, mut k) = (ctx.n, 0u32);
        while n < temp && k < 16 {
            n <<= 1;
            k += 1;
        }
        let mapped = self.bits.golomb(k, limit, self.p.qbpp)?;
        let t = mapped + ctx.kind;
        let map = t & 1;
        let magnitude = (t + map) / 2;
        let error = if (k != 0 || 2 * ctx.nn >= ctx.n) == (map == 1) {
            -magnitude
        } else {
            magnitude
        };
        if error < 0 {
            ctx.nn += 1;
        }
        ctx.a += (mapped + 1 - ctx.kind) >> 1;
        if ctx.n == self.p.reset {
            ctx.a >>= 1;
            ctx.n >>= 1;
            ctx.nn >>= 1;
        }
        ctx.n += 1;
        Ok(error)
    }

    fn end_run(&mut self) {
        self.run_index = self.run_index.saturating_sub(1);
    }
}

/// Context update and bias correction (T.87 A.6).
fn update(ctx: &mut Regular, error: i32, near: i32, reset: i32) {
    ctx.a += error.abs();
    ctx.b += error * (2 * near + 1);
    if ctx.n == reset {
        ctx.a >>= 1;
        ctx.b >>= 1;
        ctx.n >>= 1;
    }
    ctx.n += 1;
    if ctx.b + ctx.n <= 0 {
        ctx.b += ctx.n;
        if ctx.b <= -ctx.n {
            ctx.b = -ctx.n + 1;
        }
        if ctx.c > -128 {
            ctx.c -= 1;
        }
    } else if ctx.b > 0 {
        ctx.b -= ctx.n;
        if ctx.b > 0 {
            ctx.b = 0;
        }
        if ctx.c < 127 {
            ctx.c += 1;
        }
    }
}

/// The median edge detector (T.87 A.4.1).
fn predict(a: i32, b: i32, c: i32) -> i32 {
    if c >= a.max(b) {
        a.min(b)
    } else if c <= a.min(b) {
        a.max(b)
    } else {
        a + b - c
    }
}

/// Two line buffers of `width + 2` samples (one of margin each side, T.87 A.2.1's edge
/// rules: Ra = Rb and Rc = the Ra of the line above at the start, Rd = Rb at the end).
struct Lines {
    prev: Vec<i32>,
    cur: Vec<i32>,
}

impl Lines {
    fn new(width: usize) -> Self {
        Self {
            prev: vec![0; width + 2],
            cur: vec![0; width + 2],
        }
    }

    fn start(&mut self, width: usize) {
        self.prev[width + 1] = self.prev[width];
        self.cur[0] = self.prev[1];
    }

    fn next(&mut self) {
        std::mem::swap(&mut self.prev, &mut self.cur);
    }
}

/// Decodes one line of one component into `l.cur[1..=width]`.
fn decode_line(s: &mut Scan, l: &mut Lines, width: usize) -> Result<(), String> {
    let mut x = 1;
    while x <= width {
        let (a, b, c, d) = (l.cur[x - 1], l.prev[x], l.prev[x - 1], l.prev[x + 1]);
        let qs = s.p.context(a, b, c, d);
        if qs != 0 {
            l.cur[x] = s.regular(qs, predict(a, b, c))?;
            x += 1;
            continue;
        }
        let (count, eol) = s.run(width + 1 - x)?;
        l.cur[x..x + count].fill(a);
        x += count;
        if eol {
            break;
        }
        let rb = l.prev[x];
        l.cur[x] = if (a - rb).abs() <= s.p.near {
            let e = s.interruption_error(1)?;
            s.p.reconstruct(a, e)
        } else {
            let e = s.interruption_error(0)?;
            s.p.reconstruct(rb, e * if rb < a { -1 } else { 1 })
        };
        s.end_run();
        x += 1;
    }
    Ok(())
}

/// Decodes one line of sample-interleaved components (`lines[c]`, c < components).
fn decode_triplet_line(s: &mut Scan, lines: &mut [Lines], width: usize) -> Result<(), String> {
    let comps = lines.len();
    let mut x = 1;
    while x <= width {
        let mut qs = [0i32; 4];
        for (q, l) in qs.iter_mut().zip(lines.iter()) {
            *q =
                s.p.context(l.cur[x - 1], l.prev[x], l.prev[x - 1], l.prev[x + 1]);
        }
        if qs[..comps].iter().any(|&q| q != 0) {
            for (l, &q) in lines.iter_mut().zip(&qs) {
                let px = predict(l.cur[x - 1], l.prev[x], l.prev[x - 1]);
                l.cur[x] = s.regular(q, px)?;
            }
            x += 1;
            continue;
        }
        let (count, eol) = s.run(width + 1 - x)?;
        for l in lines.iter_mut() {
            let a = l.cur[x - 1];
            l.cur[x..x + count].fill(a);
        }
        x += count;
        if eol {
            break;
        }
        for l in lines.iter_mut() {
            let (a, rb) = (l.cur[x - 1], l.prev[x]);
            let e = s.interruption_error(0)?;
            l.cur[x] = s.p.reconstruct(rb, e * if rb < a { -1 } else { 1 });
        }
        s.end_run();
        x += 1;
    }
    Ok(())
}

/// Where a component's sample of pixel `i` goes in the output, in samples.
fn put(out: &mut [u16], f: &Frame, planar: bool, comp: usize, row: usize, line: &[i32]) {
    let w = f.width;
    for (x, &v) in line[1..=w].iter().enumerate() {
        let i = if planar {
            (comp * f.height + row) * w + x
        } else {
            (row * w + x) * f.components + comp
        };
        out[i] = v as u16;
    }
}

/// Decodes the scan `data` (entropy-coded bytes up to the next marker and beyond) of
/// the components `comps` with interleave mode `ilv` into `out`.
fn decode_scan(
    f: &Frame,
    p: Params,
    ilv: u8,
    comps: std::ops::Range<usize>,
    data: &[u8],
    out: &mut [u16],
) -> Result<usize, String> {
    let mut s = Scan::new(p, data);
    let n = comps.len();
    let mut lines: Vec<Lines> = (0..n).map(|_| Lines::new(f.width)).collect();
    let mut run_index = vec![0usize; n];
    for row in 0..f.height {
        for l in lines.iter_mut() {
            l.start(f.width);
        }
        if ilv == 2 && n > 1 {
            decode_triplet_line(&mut s, &mut lines, f.width)?;
        } else {
            for (c, l) in lines.iter_mut().enumerate() {
                s.run_index = run_index[c];
                decode_line(&mut s, l, f.width)?;
                run_index[c] = s.run_index;
            }
        }
        for (c, l) in lines.iter_mut().enumerate() {
            put(out, f, ilv == 0, comps.start + c, row, &l.cur);
            l.next();
        }
    }
    s.bits.check()?;
    Ok(s.bits.pos)
}

fn u16_at(data: &[u8], i: usize) -> Result<usize, String> {
    match data.get(i..i + 2) {
        Some(b) => Ok(usize::from(u16::from_be_bytes([b[0], b[1]]))),
        None => Err("a JPEG-LS marker segment cut short".into()),
    }
}

/// Reads SOF55's fields (T.87 C.2.2).
fn frame_header(seg: &[u8], max_samples: usize) -> Result<Frame, String> {
    if seg.len() < 6 {
        return Err("a JPEG-LS frame header cut short".into());
    }
    let f = Frame {
        precision: u32::from(seg[0]),
        height: u16_at(seg, 1)?,
        width: u16_at(seg, 3)?,
        components: usize::from(seg[5]),
        ..Frame::default()
    };
    if !(2..=16).contains(&f.precision) {
        return Err(format!("JPEG-LS precision {}", f.precision));
    }
    if !(1..=4).contains(&f.components) || f.width == 0 || f.height == 0 {
        return Err("a JPEG-LS frame without a size".into());
    }
    if f.width * f.height * f.components > max_samples {
        return Err("a JPEG-LS frame larger than the image".into());
    }
    for c in 0..f.components {
        if seg.get(7 + 3 * c) != Some(&0x11) {
            return Err("JPEG-LS with subsampled components is not supported".into());
        }
    }
    Ok(f)
}

/// Reads a preset-parameters segment (T.87 C.2.4.1.1); only id 1 is supported.
fn preset(f: &mut Frame, seg: &[u8]) -> Result<(), String> {
    if seg.first() != Some(&1) || seg.len() < 11 {
        return Err("JPEG-LS mapping tables or extended presets are not supported".into());
    }
    let v = |i| u16_at(seg, i).map(|x| x as i32);
    (f.maxval, f.t1, f.t2, f.t3, f.reset) = (v(1)?, v(3)?, v(5)?, v(7)?, v(9)?);
    Ok(())
}

/// Decodes a JPEG-LS codestream of at most `max_samples` samples into the bytes CharLS
/// writes: one a sample for precision <= 8, else two (little-endian).
pub(super) fn decode(data: &[u8], max_samples: usize) -> Result<Vec<u8>, String> {
    if !data.starts_with(&[0xFF, 0xD8]) {
        return Err("a JPEG-LS frame without SOI".into());
    }
    let mut frame: Option<Frame> = None;
    let mut out: Vec<u16> = Vec::new();
    let mut next_comp = 0usize;
    let mut i = 2;
    while i + 2 <= data.len() {
        if data[i] != 0xFF {
            return Err(format!("JPEG-LS: no marker at byte {i}"));
        }
        let kind = data[i + 1];
        match kind {
            0xFF => {
                i += 1;
                continue;
            }
            0xD9 => break,
            0xD0..=0xD7 => return Err("JPEG-LS restart markers are not supported".into()),
            _ => {}
        }
        let len = u16_at(data, i + 2)?;
        let seg = data
            .get(i + 4..i + 2 + len)
            .ok_or("a JPEG-LS marker segment cut short")?;
        i += 2 + len;
        match kind {
            0xF7 => {
                let f = frame_header(seg, max_samples)?;
                out = vec![0; f.width * f.height * f.components];
                frame = Some(f);
            }
            0xF8 => preset(frame.as_mut().ok_or("JPEG-LS LSE before SOF55")?, seg)?,
            0xDD => return Err("JPEG-LS restart intervals are not supported".into()),
            0xC0..=0xCF | 0xF9..=0xFE if kind != 0xC4 && kind != 0xC8 && kind != 0xCC => {
                return Err(format!("not a JPEG-LS frame (marker FF{kind:02X})"));
            }
            0xE8 if seg.starts_with(b"mrfx") && seg.get(5).is_some_and(|&t| t != 0) => {
                return Err("JPEG-LS colour transforms (HP) are not supported".into());
            }
            0xDA => {
                let f = frame.ok_or("a JPEG-LS scan before its frame header")?;
                let ns = usize::from(*seg.first().ok_or("an empty JPEG-LS scan header")?);
                let tail = seg
                    .get(1 + 2 * ns..1 + 2 * ns + 3)
                    .ok_or("a JPEG-LS scan header cut short")?;
                let (near, ilv, pt) = (i32::from(tail[0]), tail[1], tail[2]);
                if pt != 0 || ilv > 2 || (ilv == 0) != (ns == 1) && f.components > 1 {
                    return Err("JPEG-LS scan parameters not supported".into());
                }
                let comps = next_comp..next_comp + ns;
                if comps.end > f.components {
                    return Err("a JPEG-LS scan of more components than the frame".into());
                }
                let p = Params::new(&f, near)?;
                let used = decode_scan(&f, p, ilv, comps, &data[i..], &mut out)?;
                // The scan's data ends at the next marker: FF, then a byte >= 0x80.
                i += used;
                while i + 1 < data.len() && !(data[i] == 0xFF && data[i + 1] >= 0x80) {
                    i += 1;
                }
                next_comp += ns;
            }
            _ => {}
        }
    }
    let f = frame.ok_or("JPEG-LS pixel data without a frame header (SOF55)")?;
    if next_comp != f.components {
        return Err("a JPEG-LS frame missing scans".into());
    }
    Ok(if f.precision <= 8 {
        out.iter().map(|&v| v as u8).collect()
    } else {
        out.iter().flat_map(|v| v.to_le_bytes()).collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The CharLS-made cases of scripts/fixtures/jpegls-fixtures.py: (name, codestream, CharLS's
    /// decode).
    fn fixtures() -> Vec<(String, Vec<u8>, Vec<u8>)> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/jpegls");
        let mut cases: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|x| x == "jls"))
            .map(|p| {
                let name = p.file_stem().unwrap().to_string_lossy().into_owned();
                let raw = std::fs::read(p.with_extension("raw")).unwrap();
                (name, std::fs::read(&p).unwrap(), raw)
            })
            .collect();
        cases.sort();
        assert_eq!(cases.len(), 17, "the fixture set in {}", dir.display());
        cases
    }

    #[test]
    fn every_fixture_decodes_to_charls_bytes() {
        for (name, jls, raw) in fixtures() {
            let got = decode(&jls, 1 << 20).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(got.len(), raw.len(), "{name}");
            let differing = got.iter().zip(&raw).filter(|(a, b)| a != b).count();
            assert_eq!(
                differing, 0,
                "{name}: {differing} bytes differ from CharLS's"
            );
        }
    }

    /// Inserts an LSE id 1 segment after the frame header.
    fn with_preset(jls: &[u8], fields: [u16; 5]) -> Vec<u8> {
        let sof = jls.windows(2).position(|w| w == [0xFF, 0xF7]).unwrap();
        let at = sof + 2 + usize::from(u16::from_be_bytes([jls[sof + 2], jls[sof + 3]]));
        let mut lse = vec![0xFF, 0xF8, 0, 13, 1];
        for f in fields {
            lse.extend(f.to_be_bytes());
        }
        [&jls[..at], &lse, &jls[at..]].concat()
    }

    #[test]
    fn presets_that_restate_the_defaults_decode_the_same() {
        let (_, jls, raw) = fixtures()
            .into_iter()
            .find(|c| c.0 == "grey8-lossless")
            .unwrap();
        // MAXVAL 255, NEAR 0: T1 3, T2 7, T3 21, RESET 64 (T.87 C.2.4.1.1.1).
        let explicit = with_preset(&jls, [255, 3, 7, 21, 64]);
        assert_eq!(decode(&explicit, 1 << 20).unwrap(), raw);
        let zeros = with_preset(&jls, [0; 5]);
        assert_eq!(decode(&zeros, 1 << 20).unwrap(), raw);
        // Other thresholds change the contexts: the same bits decode to other samples.
        let other = with_preset(&jls, [255, 4, 9, 30, 32]);
        assert_ne!(decode(&other, 1 << 20).ok(), Some(raw));
        let disordered = with_preset(&jls, [255, 9, 4, 30, 64]);
        assert!(decode(&disordered, 1 << 20).is_err());
    }

    #[test]
    fn the_default_thresholds_are_t87s() {
        // T.87 Table C.3 for 8 bits; C.2.4.1.1.1's formulas for 12 and 16 bits and NEAR.
        assert_eq!(default_thresholds(255, 0), (3, 7, 21));
        assert_eq!(default_thresholds(4095, 0), (18, 67, 276));
        assert_eq!(default_thresholds(65535, 0), (18, 67, 276));
        assert_eq!(default_thresholds(255, 3), (12, 22, 42));
        assert_eq!(default_thresholds(3, 0), (2, 3, 3));
        // MAXVAL 31: FACTOR 8; MAX(2, 3/8 + 3) = 3, MAX(3, 7/8 + 5) = 5, MAX(4, 21/8 + 7) = 9.
        assert_eq!(default_thresholds(31, 1), (3, 5, 9));
    }

    #[test]
    fn a_frame_larger_than_the_image_is_refused_before_any_allocation() {
        let (_, jls, _) = fixtures().into_iter().next().unwrap();
        let e = decode(&jls, 100).unwrap_err();
        assert!(e.contains("larger than the image"), "{e}");
    }

    #[test]
    fn cut_and_altered_codestreams_give_errors_or_samples_never_a_panic() {
        let mut errors = 0;
        let mut decoded = 0;
        for (_, jls, raw) in fixtures() {
            for cut in (2..jls.len()).step_by(7) {
                match decode(&jls[..cut], 1 << 20) {
                    Ok(d) => {
                        decoded += 1;
                        assert_eq!(d.len(), raw.len());
                    }
                    Err(_) => errors += 1,
                }
            }
            // Every byte in turn flipped, in the headers and the scan data.
            for at in (0..jls.len()).step_by(3) {
                let mut bad = jls.clone();
                bad[at] ^= 0x5A;
                if decode(&bad, 1 << 20).is_err() {
                    errors += 1;
                }
            }
        }
        // A cut stream loses its end: most cuts are refused as cut short.
        assert!(errors > decoded, "{errors} errors, {decoded} decoded");
    }
}
