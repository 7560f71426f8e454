//! Streaming moment sums with constant memory.
//!
//! Sums are shifted by the first sample (`Σ (z − z₀)(φ − φ₀)ᵀ`), which keeps
//! the centred co-moments accurate even for regressors that barely vary
//! around a large mean, at one multiply-add per entry and sample. Each sum
//! comes with the energies that bound it (the residue test's scale).
//!
//! Samples are added [`BLOCK`] at a time by a register-tiled kernel that
//! pulp compiles for each instruction set, running the widest the CPU has
//! (AVX2 or AVX-512): a fused multiply-add per product, each sum over the
//! block's samples in order whatever the tile, so the bits do not depend on
//! the CPU (every path fuses the same operations, and a fused multiply-add
//! rounds once, the same in hardware and in `f64::mul_add`; a test runs the
//! kernel on every instruction set the CPU has).
//! [`LongRun`] gives the truncated long-run covariance sums.

use crate::dense::{Dense, SlotRows};
use nalgebra::{DMatrix, DVector};

/// Samples buffered before they are added to the sums, so that the sums are
/// loaded and stored once a block rather than once a sample.
pub const BLOCK: usize = 32;

/// Width of the kernel's tiles; buffers and sums are padded to a multiple.
const TILE: usize = 4;

fn padded(n: usize) -> usize {
    n.div_ceil(TILE) * TILE
}

/// `s += aᵀ b` for row-major `a` (`rows × wa`) and `b` (`rows × wb`), `s`
/// row-major `wa × wb`, widths multiples of [`TILE`], of which only the
/// first `used` rows of `s` are computed (the others are padding nobody
/// reads). Each entry sums its rows in order in a register tile, one fused
/// multiply-add a row, and is then added once: the same operations, in the
/// same order, on every machine, so results stay bit-identical everywhere.
#[inline(always)]
fn add_outer_products(
    s: &mut [f64],
    a: &[f64],
    b: &[f64],
    rows: usize,
    (wa, used): (usize, usize),
    wb: usize,
) {
    debug_assert!(used <= wa);
    // Tiles of four rows; the rows beyond a multiple of four are shared out
    // among the first tiles (five or six rows) rather than left to a tile
    // of one to three, whose few accumulators would wait on the latency of
    // their additions. Each entry's sum is the same whatever the tile.
    let tiles = used / TILE;
    let mut extra = used % TILE;
    if tiles == 1 && extra == 3 {
        // Seven rows in one tile would overflow the AVX registers.
        add_tile_rows::<4>(s, a, b, rows, (wa, wb), 0);
        add_tile_rows::<3>(s, a, b, rows, (wa, wb), 4);
        return;
    }
    let mut i0 = 0;
    for t in 0..tiles {
        let r = TILE + extra.div_ceil(tiles - t);
        extra -= r - TILE;
        match r {
            4 => add_tile_rows::<4>(s, a, b, rows, (wa, wb), i0),
            5 => add_tile_rows::<5>(s, a, b, rows, (wa, wb), i0),
            _ => add_tile_rows::<6>(s, a, b, rows, (wa, wb), i0),
        }
        i0 += r;
    }
    match used - i0 {
        1 => add_tile_rows::<1>(s, a, b, rows, (wa, wb), i0),
        2 => add_tile_rows::<2>(s, a, b, rows, (wa, wb), i0),
        3 => add_tile_rows::<3>(s, a, b, rows, (wa, wb), i0),
        _ => {}
    }
}

/// `R` rows of [`add_outer_products`] from row `i0`, across every column.
#[inline(always)]
fn add_tile_rows<const R: usize>(
    s: &mut [f64],
    a: &[f64],
    b: &[f64],
    rows: usize,
    (wa, wb): (usize, usize),
    i0: usize,
) {
    // Tiles two wide where the row allows (eight accumulators fill the
    // AVX registers), then one; the order of each entry's sum is the same.
    let mut j0 = 0;
    while j0 + 2 * TILE <= wb {
        add_tile::<R, { 2 * TILE }>(s, a, b, rows, (wa, wb), (i0, j0));
        j0 += 2 * TILE;
    }
    if j0 < wb {
        add_tile::<R, TILE>(s, a, b, rows, (wa, wb), (i0, j0));
    }
}

/// One `R × C` tile of [`add_outer_products`] at `(i0, j0)`.
#[inline(always)]
fn add_tile<const R: usize, const C: usize>(
    s: &mut [f64],
    a: &[f64],
    b: &[f64],
    rows: usize,
    (wa, wb): (usize, usize),
    (i0, j0): (usize, usize),
) {
    let mut acc = [[0.0f64; C]; R];
    for (ar, br) in a.chunks_exact(wa).zip(b.chunks_exact(wb)).take(rows) {
        let x = &ar[i0..i0 + R];
        let y = &br[j0..j0 + C];
        for (row, &xi) in acc.iter_mut().zip(x) {
            for (v, &yj) in row.iter_mut().zip(y) {
                *v = fused(xi, yj, *v);
            }
        }
    }
    for (r, row) in acc.iter().enumerate() {
        let out = &mut s[(i0 + r) * wb + j0..(i0 + r) * wb + j0 + C];
        for (o, v) in out.iter_mut().zip(row) {
            *o += v;
        }
    }
}

/// `x·y + acc` rounded once: the kernels' one multiply-add. Every path pulp
/// compiles the kernels for fuses it — a vector FMA on AVX2 and AVX-512,
/// `fma` from the C library on the scalar path — and a fused multiply-add
/// has one correctly rounded result, so the bits are the same on every CPU
/// (STYLE.md allows fusion in kernels, not in model evaluation, whose
/// generated code and interpreter must round alike).
#[inline(always)]
#[allow(clippy::disallowed_methods)]
fn fused(x: f64, y: f64, acc: f64) -> f64 {
    x.mul_add(y, acc)
}

/// `s[j] += Σ_rows a[row][j]²` for row-major `a` of width `w` (a multiple
/// of [`TILE`]), each entry summed over the rows in order.
#[inline(always)]
fn add_squares(s: &mut [f64], a: &[f64], rows: usize, w: usize) {
    for j0 in (0..w).step_by(TILE) {
        let mut acc = [0.0f64; TILE];
        for ar in a.chunks_exact(w).take(rows) {
            for (v, &x) in acc.iter_mut().zip(&ar[j0..j0 + TILE]) {
                *v = fused(x, x, *v);
            }
        }
        for (o, v) in s[j0..j0 + TILE].iter_mut().zip(acc) {
            *o += v;
        }
    }
}

/// One block's sums as a pulp kernel: inlined into a function compiled for
/// each instruction set, of which the widest the CPU has is run.
struct BlockKernel<'a> {
    sums: &'a mut [f64],
    zz: &'a mut [f64],
    pp: &'a mut [f64],
    zb: &'a [f64],
    fb: &'a [f64],
    rows: usize,
    wz: usize,
    /// The instrument rows in use: the instruments and the constant.
    used_z: usize,
    wf: usize,
    /// The regressors' squares are already known (kept [`RegressorRows`]).
    squares_known: bool,
}

impl pulp::WithSimd for BlockKernel<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        add_outer_products(
            self.sums,
            self.zb,
            self.fb,
            self.rows,
            (self.wz, self.used_z),
            self.wf,
        );
        add_squares(self.zz, self.zb, self.rows, self.wz);
        if !self.squares_known {
            add_squares(self.pp, self.fb, self.rows, self.wf);
        }
    }
}

/// The regressor side of one record's moment sums, kept from a pass for the
/// later passes that differ only in their instruments (the refinements of
/// an IV estimate): every block row `[φ − φ₀, t − t₀, 1]` as the
/// accumulator wrote it, with the shift and the sums of squares. Later
/// passes read these rows instead of evaluating and gathering the
/// regressors again, and get the same bits.
#[derive(Clone, Debug)]
pub struct RegressorRows {
    p: usize,
    wf: usize,
    phi0: Vec<f64>,
    t0: f64,
    /// Row-major `samples × wf`.
    rows: Vec<f64>,
    s_pp: Vec<f64>,
    /// The sums of squares of the full blocks' rows only (padded width):
    /// where an accumulation over these rows stood before its last, partial
    /// block, which a resumed accumulation adds again.
    s_pp_blocks: Vec<f64>,
}

impl RegressorRows {
    /// Samples kept.
    pub fn len(&self) -> usize {
        self.rows.len() / self.wf
    }
    /// True when no sample was kept.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }
    /// Bytes held (room reserved included).
    pub fn bytes(&self) -> usize {
        self.rows.capacity() * std::mem::size_of::<f64>()
    }
}

/// Where an accumulation that keeps its regressor rows stood after a
/// record's samples, before its last (partial) block was added: the sums
/// of the full blocks and the instruments of the rows after them. With the
/// kept rows, an accumulation over a longer record that begins with the
/// same samples goes on from here ([`MomentAccumulator::keep_rows_resuming`])
/// and adds the same blocks as one from the start: the same bits.
#[derive(Clone, Debug)]
pub struct PartialSums {
    n: usize,
    z0: Vec<f64>,
    sums: Vec<f64>,
    s_zz: Vec<f64>,
    s_pp: Vec<f64>,
    /// The instrument rows of the block being filled.
    zb: Vec<f64>,
    filled: usize,
}

impl PartialSums {
    /// Whether these sums are where an accumulation of as many instruments
    /// as regressors stood after `rows`' samples (their number and shapes).
    pub fn continues(&self, rows: &RegressorRows) -> bool {
        let wz = padded(rows.p + 1);
        self.n == rows.len()
            && self.filled < BLOCK
            && self.filled <= self.n
            && self.z0.len() == rows.p
            && self.sums.len() == wz * rows.wf
            && self.s_zz.len() == wz
            && self.s_pp.len() == rows.wf
            && self.zb.len() == self.filled * wz
    }
    /// Whether these sums are where an accumulation of as many instruments
    /// against the first of `rows` stood (their shapes, and no more
    /// samples than `rows` has).
    pub fn continues_over(&self, rows: &RegressorRows) -> bool {
        let wz = padded(rows.p + 1);
        self.n <= rows.len()
            && self.filled < BLOCK
            && self.n % BLOCK == self.filled
            && self.z0.len() == rows.p
            && self.sums.len() == wz * rows.wf
            && self.s_zz.len() == wz
            && self.zb.len() == self.filled * wz
    }
    /// Samples accumulated.
    pub fn len(&self) -> usize {
        self.n
    }
    /// True before the first sample.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
}

/// Shifted cross-moment sums of instruments `z`, regressors `φ` and target
/// `t`: what one experiment contributes to the moment equations, whatever
/// its length (`O(m·p)` numbers).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct CrossMoments {
    /// Samples.
    pub n: usize,
    m: usize,
    p: usize,
    z0: Vec<f64>,
    phi0: Vec<f64>,
    t0: f64,
    /// `Σ (z − z₀)(φ − φ₀)ᵀ`, row-major `m × p`.
    s_zphi: Vec<f64>,
    s_zt: Vec<f64>,
    s_z: Vec<f64>,
    s_phi: Vec<f64>,
    s_t: f64,
    /// `Σ (z − z₀)²` and `Σ (φ − φ₀)²` per entry: the scales against which a
    /// moment is judged to be rounding residue.
    s_zz: Vec<f64>,
    s_pp: Vec<f64>,
}

/// Accumulates [`CrossMoments`] a block of samples at a time: each sample
/// is written (shifted by the first one) into a row of the block buffers,
/// `[z − z₀, 1]` and `[φ − φ₀, t − t₀, 1]`, and a full block is added by one
/// small matrix product that yields every sum at once.
#[derive(Clone, Debug)]
pub struct MomentAccumulator {
    n: usize,
    m: usize,
    p: usize,
    z0: Vec<f64>,
    phi0: Vec<f64>,
    t0: f64,
    /// Padded widths of the instrument and regressor rows.
    wz: usize,
    wf: usize,
    /// `Σ [z − z₀, 1]ᵀ [φ − φ₀, t − t₀, 1]`, row-major `wz × wf`.
    sums: Vec<f64>,
    s_zz: Vec<f64>,
    s_pp: Vec<f64>,
    zb: Vec<f64>,
    fb: Vec<f64>,
    filled: usize,
    /// Keeping every regressor row: `fb` then grows with the record, and
    /// the current block starts at row `base`.
    keeping: bool,
    base: usize,
}

/// The bytes [`MomentAccumulator::keep_rows`] takes for `samples` rows of
/// `p` regressors (before any room reserved for a longer record).
pub fn kept_rows_bytes(p: usize, samples: usize) -> usize {
    (samples.saturating_add(BLOCK))
        .saturating_mul(padded(p + 2))
        .saturating_mul(std::mem::size_of::<f64>())
}

impl MomentAccumulator {
    /// Empty sums for `m` instruments and `p` regressors.
    pub fn new(m: usize, p: usize) -> MomentAccumulator {
        let (wz, wf) = (padded(m + 1), padded(p + 2));
        let mut zb = vec![0.0; BLOCK * wz];
        let mut fb = vec![0.0; BLOCK * wf];
        // The constant columns: `Σ 1·(φ − φ₀)`, `Σ 1·(t − t₀)` and `n` come out
        // of the same product.
        for row in zb.chunks_exact_mut(wz) {
            row[m] = 1.0;
        }
        for row in fb.chunks_exact_mut(wf) {
            row[p + 1] = 1.0;
        }
        MomentAccumulator {
            n: 0,
            m,
            p,
            z0: vec![0.0; m],
            phi0: vec![0.0; p],
            t0: 0.0,
            wz,
            wf,
            sums: vec![0.0; wz * wf],
            s_zz: vec![0.0; wz],
            s_pp: vec![0.0; wf],
            zb,
            fb,
            filled: 0,
            keeping: false,
            base: 0,
        }
    }

    /// Keeps every regressor row for [`MomentAccumulator::finish_keeping`]
    /// (`samples` rows expected, room reserved for `reserve` when more, for
    /// a longer record that will begin with these rows): rows are written
    /// where they are kept, into zeroed memory.
    pub fn keep_rows(&mut self, samples: usize, reserve: usize) {
        if self.n == 0 {
            self.keeping = true;
            let mut fb = Vec::with_capacity((samples.max(reserve) + BLOCK) * self.wf);
            fb.resize((samples + BLOCK) * self.wf, 0.0);
            self.fb = fb;
        }
    }

    /// Keeps every regressor row, as [`MomentAccumulator::keep_rows`], the
    /// first ones known: `prefix`, kept by an accumulation over the first
    /// samples of the same record with the same regressors. Their samples are
    /// then pushed by [`MomentAccumulator::push_over_kept_row`] and those after
    /// them as usual; the sums and rows are those of pushing every sample.
    pub fn keep_rows_after(&mut self, prefix: RegressorRows, samples: usize) {
        // Rows are kept per plan, so the prefix has this accumulator's shape.
        debug_assert!(self.n == 0 && prefix.p == self.p && prefix.wf == self.wf);
        self.keeping = true;
        self.phi0 = prefix.phi0;
        self.t0 = prefix.t0;
        self.fb = prefix.rows;
        self.fb
            .reserve((samples + BLOCK).saturating_sub(self.fb.len() / self.wf) * self.wf);
    }

    /// Where this accumulation stands (see [`PartialSums`]); `None` unless
    /// it keeps its regressor rows, which a resumed accumulation needs.
    pub fn partial(&self) -> Option<PartialSums> {
        self.keeping.then(|| self.partial_instruments())
    }

    /// Goes on from `from` (its samples already accumulated), except the
    /// regressors' squares.
    fn go_on_from(&mut self, from: PartialSums) {
        self.n = from.n;
        self.z0 = from.z0;
        self.sums = from.sums;
        self.s_zz = from.s_zz;
        self.zb[..from.zb.len()].copy_from_slice(&from.zb);
        self.filled = from.filled;
    }

    /// Keeps every regressor row, as [`MomentAccumulator::keep_rows_after`],
    /// and goes on from `from`, where an accumulation over `prefix`'s samples
    /// stood ([`PartialSums::continues`] them): the next sample pushed is the
    /// one after them.
    pub fn keep_rows_resuming(&mut self, prefix: RegressorRows, from: PartialSums, samples: usize) {
        debug_assert!(self.n == 0 && self.m == self.p && from.continues(&prefix));
        // The rows' own squares: `from` may come from an accumulation
        // against kept rows, which sums none.
        let s_pp = prefix.s_pp_blocks.clone();
        self.keep_rows_after(prefix, samples);
        self.base = from.n - from.filled;
        self.go_on_from(from);
        self.s_pp = s_pp;
    }

    /// Where an accumulation by [`MomentAccumulator::push_instruments`]
    /// stands (see [`PartialSums`]; the regressors' squares are the kept
    /// rows' own).
    pub fn partial_instruments(&self) -> PartialSums {
        PartialSums {
            n: self.n,
            z0: self.z0.clone(),
            sums: self.sums.clone(),
            s_zz: self.s_zz.clone(),
            s_pp: self.s_pp.clone(),
            zb: self.zb[..self.filled * self.wz].to_vec(),
            filled: self.filled,
        }
    }

    /// Goes on from `from`, where an accumulation of as many instruments
    /// against the first rows of `kept` stood
    /// ([`PartialSums::continues_over`]): the next sample pushed by
    /// [`MomentAccumulator::push_instruments`] is the one after them, and
    /// the sums are those of pushing every sample.
    pub fn resume_instruments(&mut self, from: PartialSums, kept: &RegressorRows) {
        debug_assert!(self.n == 0 && self.m == kept.p && from.continues_over(kept));
        self.go_on_from(from);
    }

    /// Adds one sample whose regressors and target are already in its kept
    /// row ([`MomentAccumulator::keep_rows_after`]): its instruments are the
    /// entries `cols` of the dense row `z`, or (`z` empty, least squares) the
    /// kept regressors themselves. The same bits as
    /// [`MomentAccumulator::push_columns`] of the same sample.
    #[inline]
    pub fn push_over_kept_row<D: Dense>(&mut self, z: D, cols: &[usize]) {
        let (m, r) = (self.m, self.filled);
        let at = (self.base + r) * self.wf;
        if z.is_empty() {
            // `z − z₀` of least squares is `φ − φ₀`, which the row holds.
            debug_assert!(m == self.p);
            if self.n == 0 {
                self.z0.clone_from(&self.phi0);
            }
            let (zb, fb) = (&mut self.zb, &self.fb);
            zb[r * self.wz..r * self.wz + m].copy_from_slice(&fb[at..at + m]);
        } else {
            if self.n == 0 {
                for (a, &c) in self.z0.iter_mut().zip(cols) {
                    *a = z.at(c);
                }
            }
            let zr = &mut self.zb[r * self.wz..r * self.wz + m];
            for ((a, &c), z0) in zr.iter_mut().zip(cols).zip(&self.z0) {
                *a = z.at(c) - z0;
            }
        }
        self.n += 1;
        self.filled += 1;
        if self.filled == BLOCK {
            self.flush();
        }
    }

    /// Where the next regressor row starts in `fb` (room made if needed).
    #[inline]
    fn next_row(&mut self) -> usize {
        let at = (self.base + self.filled) * self.wf;
        if at + self.wf > self.fb.len() {
            self.fb.resize(at + BLOCK * self.wf, 0.0);
        }
        at
    }

    /// Adds one sample.
    #[inline]
    pub fn push(&mut self, z: &[f64], phi: &[f64], t: f64) {
        self.push_with(
            |zs, fs| {
                zs.copy_from_slice(&z[..zs.len()]);
                fs.copy_from_slice(&phi[..fs.len()]);
            },
            t,
        );
    }

    /// Adds one sample whose instruments and regressors are the entries
    /// `cols` of the dense rows `z` and `phi` (as many instruments as
    /// regressors), gathered and shifted in one sweep.
    #[inline]
    pub fn push_columns<D: Dense>(&mut self, z: D, phi: D, cols: &[usize], t: f64) {
        debug_assert!(self.m == cols.len() && self.p == cols.len());
        if self.n == 0 {
            for ((a, b), &c) in self.z0.iter_mut().zip(self.phi0.iter_mut()).zip(cols) {
                *a = z.at(c);
                *b = phi.at(c);
            }
            self.t0 = t;
        }
        let (m, p, r) = (self.m, self.p, self.filled);
        let at = self.next_row();
        let zr = &mut self.zb[r * self.wz..r * self.wz + m];
        let fr = &mut self.fb[at..at + p];
        for (((a, b), &c), (z0, p0)) in zr
            .iter_mut()
            .zip(fr.iter_mut())
            .zip(cols)
            .zip(self.z0.iter().zip(&self.phi0))
        {
            *a = z.at(c) - z0;
            *b = phi.at(c) - p0;
        }
        self.fb[at + p] = t - self.t0;
        self.fb[at + p + 1] = 1.0;
        self.n += 1;
        self.filled += 1;
        if self.filled == BLOCK {
            self.flush();
        }
    }

    /// Adds a block's samples, as [`MomentAccumulator::push_columns`] one
    /// by one: instruments and regressors the slots `cols` of `z` and
    /// `phi` (evaluated slot-major), targets `t`, one a sample. Written a
    /// slot at a time across the samples when they fill the buffer from
    /// its start: the same values in the same rows, so the same bits.
    pub fn push_block(&mut self, z: SlotRows, phi: SlotRows, cols: &[usize], t: &[f64]) {
        let nb = t.len();
        if self.filled != 0 || nb == 0 || nb > BLOCK {
            for (s, &t) in t.iter().enumerate() {
                self.push_columns(z.column(s), phi.column(s), cols, t);
            }
            return;
        }
        debug_assert!(self.m == cols.len() && self.p == cols.len());
        if self.n == 0 {
            for ((a, b), &c) in self.z0.iter_mut().zip(self.phi0.iter_mut()).zip(cols) {
                *a = z.row(c)[0];
                *b = phi.row(c)[0];
            }
            self.t0 = t[0];
        }
        let (p, wz, wf) = (self.p, self.wz, self.wf);
        let at = self.base * wf;
        if at + nb * wf > self.fb.len() {
            self.fb.resize(at + BLOCK * wf, 0.0);
        }
        let fb = &mut self.fb[at..at + nb * wf];
        for (i, &c) in cols.iter().enumerate() {
            let (z0, p0) = (self.z0[i], self.phi0[i]);
            for (row, &v) in self.zb.chunks_exact_mut(wz).zip(z.row(c)) {
                row[i] = v - z0;
            }
            for (row, &v) in fb.chunks_exact_mut(wf).zip(phi.row(c)) {
                row[i] = v - p0;
            }
        }
        for (row, &t) in fb.chunks_exact_mut(wf).zip(t) {
            row[p] = t - self.t0;
            row[p + 1] = 1.0;
        }
        self.n += nb;
        self.filled = nb;
        if self.filled == BLOCK {
            self.flush();
        }
    }

    /// `write(z, φ)` fills the sample's instruments and regressors in place.
    #[inline]
    fn push_with(&mut self, write: impl FnOnce(&mut [f64], &mut [f64]), t: f64) {
        let (m, p) = (self.m, self.p);
        let at = self.next_row();
        let zr = &mut self.zb[self.filled * self.wz..self.filled * self.wz + m];
        let fr = &mut self.fb[at..at + p];
        write(zr, fr);
        if self.n == 0 {
            self.z0.copy_from_slice(zr);
            self.phi0.copy_from_slice(fr);
            self.t0 = t;
        }
        for (v, c) in zr.iter_mut().zip(&self.z0) {
            *v -= c;
        }
        for (v, c) in fr.iter_mut().zip(&self.phi0) {
            *v -= c;
        }
        self.fb[at + p] = t - self.t0;
        self.fb[at + p + 1] = 1.0;
        self.n += 1;
        self.filled += 1;
        if self.filled == BLOCK {
            self.flush();
        }
    }

    /// Adds one sample whose instruments are the entries `cols` of the dense
    /// row `z` and whose regressors and target are `kept`'s next row (the
    /// same sample of the same record).
    #[inline]
    pub fn push_instruments<D: Dense>(&mut self, z: D, cols: &[usize], kept: &RegressorRows) {
        debug_assert!(self.m == cols.len() && self.p == kept.p && self.wf == kept.wf);
        if self.n == 0 {
            for (a, &c) in self.z0.iter_mut().zip(cols) {
                *a = z.at(c);
            }
        }
        let (m, r) = (self.m, self.filled);
        let zr = &mut self.zb[r * self.wz..r * self.wz + m];
        for ((a, &c), z0) in zr.iter_mut().zip(cols).zip(&self.z0) {
            *a = z.at(c) - z0;
        }
        self.n += 1;
        self.filled += 1;
        if self.filled == BLOCK {
            self.flush_kept(kept);
        }
    }

    /// Adds the buffered instruments against `kept`'s rows of the same samples.
    fn flush_kept(&mut self, kept: &RegressorRows) {
        let rows = self.filled;
        let first = self.n - rows;
        let Some(fb) = kept.rows.get(first * self.wf..(first + rows) * self.wf) else {
            // More samples than kept: a different record (never for one
            // record's passes); leave the sums unusable rather than wrong.
            self.sums.fill(f64::NAN);
            self.filled = 0;
            return;
        };
        pulp::Arch::new().dispatch(BlockKernel {
            sums: &mut self.sums,
            zz: &mut self.s_zz,
            pp: &mut self.s_pp,
            zb: &self.zb,
            fb,
            rows,
            wz: self.wz,
            used_z: self.m + 1,
            wf: self.wf,
            squares_known: true,
        });
        self.filled = 0;
    }

    /// The sums of every sample pushed by [`MomentAccumulator::push_instruments`].
    pub fn finish_with(mut self, kept: &RegressorRows) -> CrossMoments {
        if self.filled > 0 {
            self.flush_kept(kept);
        }
        if self.n != kept.len() {
            self.sums.fill(f64::NAN);
        }
        self.phi0.clone_from(&kept.phi0);
        self.t0 = kept.t0;
        self.s_pp[..self.p].copy_from_slice(&kept.s_pp);
        self.finish()
    }

    /// The sums, and the regressor rows kept since [`MomentAccumulator::keep_rows`].
    pub fn finish_keeping(mut self) -> (CrossMoments, Option<RegressorRows>) {
        let s_pp_blocks = self.s_pp.clone();
        self.flush();
        let rows = self.keeping.then(|| {
            let mut rows = std::mem::take(&mut self.fb);
            rows.truncate(self.n * self.wf);
            RegressorRows {
                p: self.p,
                wf: self.wf,
                phi0: self.phi0.clone(),
                t0: self.t0,
                rows,
                s_pp: self.s_pp[..self.p].to_vec(),
                s_pp_blocks,
            }
        });
        (self.finish(), rows)
    }

    fn flush(&mut self) {
        let rows = self.filled;
        if rows == 0 {
            return;
        }
        let block = self.base * self.wf..(self.base + rows) * self.wf;
        // Compiled for the widest SIMD this CPU has (pulp dispatches at run
        // time); every lane does the same fused multiply-add, so the
        // bits do not depend on the CPU.
        pulp::Arch::new().dispatch(BlockKernel {
            sums: &mut self.sums,
            zz: &mut self.s_zz,
            pp: &mut self.s_pp,
            zb: &self.zb,
            fb: &self.fb[block],
            rows,
            wz: self.wz,
            used_z: self.m + 1,
            wf: self.wf,
            squares_known: false,
        });
        if self.keeping {
            self.base += rows;
        }
        self.filled = 0;
    }

    /// The sums of every sample pushed.
    pub fn finish(mut self) -> CrossMoments {
        self.flush();
        let (m, p, wf) = (self.m, self.p, self.wf);
        let at = |i: usize, j: usize| self.sums[i * wf + j];
        CrossMoments {
            n: self.n,
            m,
            p,
            s_zphi: (0..m)
                .flat_map(|i| (0..p).map(move |j| (i, j)))
                .map(|(i, j)| at(i, j))
                .collect(),
            s_zt: (0..m).map(|i| at(i, p)).collect(),
            s_z: (0..m).map(|i| at(i, p + 1)).collect(),
            s_phi: (0..p).map(|j| at(m, j)).collect(),
            s_t: at(m, p),
            z0: self.z0,
            phi0: self.phi0,
            t0: self.t0,
            s_zz: self.s_zz[..m].to_vec(),
            s_pp: self.s_pp[..p].to_vec(),
        }
    }
}

impl CrossMoments {
    /// Mean of the instruments.
    pub fn mean_z(&self) -> DVector<f64> {
        let n = self.n.max(1) as f64;
        DVector::from_iterator(
            self.m,
            self.z0.iter().zip(&self.s_z).map(|(a, s)| a + s / n),
        )
    }
    /// Mean of the regressors.
    pub fn mean_phi(&self) -> DVector<f64> {
        let n = self.n.max(1) as f64;
        DVector::from_iterator(
            self.p,
            self.phi0.iter().zip(&self.s_phi).map(|(a, s)| a + s / n),
        )
    }
    /// Mean of the target.
    pub fn mean_t(&self) -> f64 {
        if self.n == 0 {
            self.t0
        } else {
            self.t0 + self.s_t / self.n as f64
        }
    }

    /// `Σ_k ‖z(k) − c‖²`: the instruments' energy about a centre `c`.
    pub fn z_energy(&self, c: &DVector<f64>) -> f64 {
        let n = self.n as f64;
        (0..self.m)
            .map(|i| {
                let d = self.z0[i] - c[i];
                (self.s_zz[i] + 2.0 * d * self.s_z[i] + n * d * d).max(0.0)
            })
            .sum()
    }
    /// `Σ_k φ_j(k)²` per regressor (uncentred).
    pub fn phi_energy(&self) -> Vec<f64> {
        let n = self.n as f64;
        (0..self.p)
            .map(|j| {
                let a = self.phi0[j];
                (self.s_pp[j] + 2.0 * a * self.s_phi[j] + n * a * a).max(0.0)
            })
            .collect()
    }

    /// The centred co-moments `Σ (z − z̄)(φ − φ̄)ᵀ` and `Σ (z − z̄)(t − t̄)`:
    /// the moment equations `Σ (z − z̄)(t − φᵀϑ)` with instruments centred per
    /// experiment.
    pub fn centred(&self) -> (DMatrix<f64>, DVector<f64>) {
        let n = self.n.max(1) as f64;
        let h = DMatrix::from_fn(self.m, self.p, |i, j| {
            self.s_zphi[i * self.p + j] - self.s_z[i] * self.s_phi[j] / n
        });
        let g = DVector::from_fn(self.m, |i, _| self.s_zt[i] - self.s_z[i] * self.s_t / n);
        (h, g)
    }

    /// The moment equations `Σ (z − c)(t − φᵀϑ) = g − Hϑ` with instruments
    /// centred at `c` (a pooled mean, or zero for no centring): `(H, g)`.
    pub fn about(&self, c: &DVector<f64>) -> (DMatrix<f64>, DVector<f64>) {
        let (h, g) = self.centred();
        if self.n == 0 {
            return (h, g);
        }
        let n = self.n as f64;
        let dz = self.mean_z() - c;
        (
            h + &dz * self.mean_phi().transpose() * n,
            g + &dz * (self.mean_t() * n),
        )
    }
}

/// `s += aᵀ b` (both `rows × w`, row-major) by [`add_outer_products`],
/// compiled for the widest SIMD the CPU has.
/// Only the first `used` rows of `s` are computed.
fn add_products(s: &mut [f64], a: &[f64], b: &[f64], rows: usize, (w, used): (usize, usize)) {
    struct Products<'a> {
        s: &'a mut [f64],
        a: &'a [f64],
        b: &'a [f64],
        rows: usize,
        w: usize,
        used: usize,
    }
    impl pulp::WithSimd for Products<'_> {
        type Output = ();
        #[inline(always)]
        fn with_simd<S: pulp::Simd>(self, _simd: S) {
            add_outer_products(
                self.s,
                self.a,
                self.b,
                self.rows,
                (self.w, self.used),
                self.w,
            );
        }
    }
    pulp::Arch::new().dispatch(Products {
        s,
        a,
        b,
        rows,
        w,
        used,
    });
}

/// Long-run covariance sums of a vector series `ζ_k` truncated at `lags`
/// (uniform weights, the right kernel for the MA(1) residual of an Euler
/// difference): `Σ ζ_k ζ_kᵀ + Σ_{j=1..L} Σ (ζ_k ζ_{k−j}ᵀ + ζ_{k−j} ζ_kᵀ)`.
/// With `s_k = Σ_{j=1..L} ζ_{k−j}` this is the symmetric part of
/// `M = Σ ζ_k (ζ_k + 2 s_k)ᵀ`: one product per block instead of `L + 1`.
/// Samples are buffered [`BLOCK`] at a time behind the last `lags` of the
/// previous block (zeros before the first sample).
#[derive(Clone, Debug)]
pub struct LongRun {
    lags: usize,
    dim: usize,
    /// Padded row width.
    w: usize,
    /// `M = Σ ζ_k (ζ_k + 2 s_k)ᵀ`, row-major `w × w`.
    sums: Vec<f64>,
    /// `lags` rows of history, then up to [`BLOCK`] new rows.
    buf: Vec<f64>,
    /// `ζ_k + 2 s_k` of the block's rows.
    with_lags: Vec<f64>,
    filled: usize,
    /// Samples seen.
    pub n: usize,
}

impl LongRun {
    /// Empty sums for dimension `m` with `lags ≥ 1`.
    pub fn new(m: usize, lags: usize) -> LongRun {
        let lags = lags.max(1);
        let w = padded(m);
        LongRun {
            lags,
            dim: m,
            w,
            sums: vec![0.0; w * w],
            buf: vec![0.0; (lags + BLOCK) * w],
            with_lags: vec![0.0; BLOCK * w],
            filled: 0,
            n: 0,
        }
    }
    /// Adds `ζ_k`.
    pub fn push(&mut self, zeta: &DVector<f64>) {
        self.push_with(|row| row.copy_from_slice(zeta.as_slice()));
    }
    /// Adds the `ζ_k` that `fill` writes into its (zeroed) row.
    #[inline]
    pub fn push_with(&mut self, fill: impl FnOnce(&mut [f64])) {
        let start = (self.lags + self.filled) * self.w;
        let row = &mut self.buf[start..start + self.dim];
        row.fill(0.0);
        fill(row);
        self.filled += 1;
        self.n += 1;
        if self.filled == BLOCK {
            self.flush();
        }
    }

    /// Adds the `ζ` of `n` samples that `fill` writes into their zeroed
    /// rows (`fill(rows, w)`: sample `s`'s row at `rows[s·w..]`), as `n`
    /// calls of [`LongRun::push_with`] would — when they begin a block
    /// (`false`, and nothing added, otherwise).
    #[inline]
    pub fn push_rows_with(&mut self, n: usize, fill: impl FnOnce(&mut [f64], usize)) -> bool {
        // No rows to lay out without a dimension (`w` is then 0).
        if self.filled != 0 || n == 0 || n > BLOCK || self.w == 0 {
            return false;
        }
        let (w, dim) = (self.w, self.dim);
        let rows = &mut self.buf[self.lags * w..(self.lags + n) * w];
        for row in rows.chunks_exact_mut(w) {
            row[..dim].fill(0.0);
        }
        fill(rows, w);
        self.filled = n;
        self.n += n;
        if self.filled == BLOCK {
            self.flush();
        }
        true
    }

    fn flush(&mut self) {
        let (rows, w, lags) = (self.filled, self.w, self.lags);
        if rows == 0 {
            return;
        }
        for r in 0..rows {
            let out = &mut self.with_lags[r * w..(r + 1) * w];
            out.fill(0.0);
            for j in 1..=lags {
                let earlier = &self.buf[(lags + r - j) * w..(lags + r - j + 1) * w];
                for (o, e) in out.iter_mut().zip(earlier) {
                    *o += e;
                }
            }
            let current = &self.buf[(lags + r) * w..(lags + r + 1) * w];
            for (o, c) in out.iter_mut().zip(current) {
                *o = c + 2.0 * *o;
            }
        }
        let current = &self.buf[lags * w..(lags + rows) * w];
        add_products(
            &mut self.sums,
            current,
            &self.with_lags,
            rows,
            (w, self.dim),
        );
        // The last `lags` rows become the next block's history.
        self.buf.copy_within(rows * w..(rows + lags) * w, 0);
        self.filled = 0;
    }

    /// The long-run sum, made positive semi-definite by clipping negative
    /// eigenvalues (truncated kernels need not be PSD in finite samples).
    pub fn sum_psd(mut self) -> DMatrix<f64> {
        self.flush();
        let (m, w) = (self.dim, self.w);
        if m == 0 {
            return DMatrix::zeros(0, 0);
        }
        let sym = DMatrix::from_fn(m, m, |i, j| {
            0.5 * (self.sums[i * w + j] + self.sums[j * w + i])
        });
        // Unbounded iterations on a NaN: a non-finite sum is returned as it
        // is (the covariance then reports it as not finite).
        if !sym.iter().all(|v| v.is_finite()) {
            return sym;
        }
        let eig = sym.clone().symmetric_eigen();
        if eig.eigenvalues.iter().all(|v| *v >= 0.0) {
            return sym;
        }
        let clipped = eig.eigenvalues.map(|v| v.max(0.0));
        &eig.eigenvectors * DMatrix::from_diagonal(&clipped) * eig.eigenvectors.transpose()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shifted_sums_match_two_pass_covariance() {
        let zs: Vec<[f64; 2]> = (0..50)
            .map(|k| [1e6 + (k as f64).sin(), 3.0 + 0.1 * k as f64])
            .collect();
        let mut acc = MomentAccumulator::new(2, 2);
        for z in &zs {
            acc.push(z, z, z[0] + 2.0 * z[1]);
        }
        let m = acc.finish();
        let (c, ct) = m.centred();
        let (c2, ct2) = m.about(&m.mean_z());
        assert!((&c - c2).abs().max() < 1e-9 && (&ct - ct2).abs().max() < 1e-9);
        let mut exact = DMatrix::zeros(2, 2);
        let mut exact_t = DVector::zeros(2);
        let mu = [
            zs.iter().map(|z| z[0]).sum::<f64>() / 50.0,
            zs.iter().map(|z| z[1]).sum::<f64>() / 50.0,
        ];
        let mt = mu[0] + 2.0 * mu[1];
        for z in &zs {
            let d = DVector::from_row_slice(&[z[0] - mu[0], z[1] - mu[1]]);
            exact += &d * d.transpose();
            exact_t += &d * (z[0] + 2.0 * z[1] - mt);
        }
        assert!((c - exact).abs().max() < 1e-6);
        assert!((ct - exact_t).abs().max() < 1e-6);
    }

    /// The block kernel gives the same bits on every instruction set this
    /// CPU has (pulp dispatches to the widest): each entry is summed in
    /// row order with fused multiply-adds, whatever the lanes.
    #[test]
    fn block_kernel_bits_do_not_depend_on_the_instruction_set() {
        let (m, p) = (13, 12);
        let (wz, wf) = (padded(m + 1), padded(p + 2));
        let rows = BLOCK - 3;
        // Values over many orders of magnitude, so any reassociation shows.
        let value = |k: usize| {
            let x = ((k * 7919) % 104_729) as f64 / 104_729.0 - 0.5;
            const SCALES: [f64; 13] = [
                1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6,
            ];
            x * SCALES[k % 13]
        };
        let zb: Vec<f64> = (0..BLOCK * wz).map(value).collect();
        let fb: Vec<f64> = (0..BLOCK * wf).map(|k| value(k + 31)).collect();
        let run = |arch: &dyn Fn(BlockKernel<'_>)| {
            let mut sums: Vec<f64> = (0..wz * wf).map(|k| value(k + 7)).collect();
            let mut zz = vec![0.25; wz];
            let mut pp = vec![0.5; wf];
            arch(BlockKernel {
                sums: &mut sums,
                zz: &mut zz,
                pp: &mut pp,
                zb: &zb,
                fb: &fb,
                rows,
                wz,
                used_z: m + 1,
                wf,
                squares_known: false,
            });
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            (bits(&sums), bits(&zz), bits(&pp))
        };
        let scalar = run(&|k| pulp::Simd::vectorize(pulp::Scalar::new(), k));
        assert_eq!(run(&|k| pulp::Arch::new().dispatch(k)), scalar);
        #[cfg(target_arch = "x86_64")]
        {
            if let Some(simd) = pulp::x86::V3::try_new() {
                assert_eq!(run(&|k| pulp::Simd::vectorize(simd, k)), scalar);
            }
            if let Some(simd) = pulp::x86::V4::try_new() {
                assert_eq!(run(&|k| pulp::Simd::vectorize(simd, k)), scalar);
            }
        }
    }

    /// Whatever the tiles the rows in use are cut into, every entry is its
    /// rows' products summed in row order from zero, each product fused
    /// into the sum (one rounding), then added once.
    #[test]
    fn block_products_are_each_entry_summed_in_row_order() {
        let value = |k: usize| {
            let x = ((k * 7919) % 104_729) as f64 / 104_729.0 - 0.5;
            x * [1e-3, 1.0, 1e3, 1e-1, 1e2][k % 5]
        };
        for used in 1..=17 {
            let (wa, wb) = (padded(used), 12);
            let rows = 29;
            let a: Vec<f64> = (0..rows * wa).map(value).collect();
            let b: Vec<f64> = (0..rows * wb).map(|k| value(k + 3)).collect();
            let start: Vec<f64> = (0..wa * wb).map(|k| value(k + 11)).collect();
            let mut got = start.clone();
            pulp::Arch::new().dispatch(BlockKernel {
                sums: &mut got,
                zz: &mut vec![0.0; wa],
                pp: &mut [],
                zb: &a,
                fb: &b,
                rows,
                wz: wa,
                used_z: used,
                wf: wb,
                squares_known: true,
            });
            for i in 0..used {
                for j in 0..wb {
                    let mut sum = 0.0;
                    for r in 0..rows {
                        sum = fused(a[r * wa + i], b[r * wb + j], sum);
                    }
                    let want = start[i * wb + j] + sum;
                    assert_eq!(
                        got[i * wb + j].to_bits(),
                        want.to_bits(),
                        "{used} rows: ({i}, {j})"
                    );
                }
            }
        }
    }

    #[test]
    fn long_run_of_white_noise_is_its_covariance_sum() {
        let mut lr = LongRun::new(1, 1);
        for k in 0..4 {
            lr.push(&DVector::from_element(
                1,
                if k % 2 == 0 { 1.0 } else { -1.0 },
            ));
        }
        // 4 · 1 + 2 · (−1) · 3 = −2 → clipped to 0.
        assert_eq!(lr.sum_psd()[(0, 0)], 0.0);
    }

    #[test]
    fn blocked_long_run_sums_match_the_definition() {
        // 3 lags, 100 samples: several blocks, history carried across them.
        let (m, lags) = (5, 3);
        let zs: Vec<Vec<f64>> = (0..100)
            .map(|k| {
                (0..m)
                    .map(|i| ((k * 7 + i * 3) as f64 * 0.37).sin())
                    .collect()
            })
            .collect();
        let mut lr = LongRun::new(m, lags);
        for z in &zs {
            lr.push(&DVector::from_row_slice(z));
        }
        let mut exact = DMatrix::zeros(m, m);
        for (k, z) in zs.iter().enumerate() {
            let zk = DVector::from_row_slice(z);
            exact += &zk * zk.transpose();
            for j in 1..=lags.min(k) {
                let zj = DVector::from_row_slice(&zs[k - j]);
                exact += &zk * zj.transpose() + &zj * zk.transpose();
            }
        }
        let got = lr.sum_psd();
        // The definition need not be PSD; these data keep it so.
        assert!((got - &exact).abs().max() < 1e-9 * exact.abs().max());
    }

    /// Rows of `ζ` added a block at a time give the bits of the same rows
    /// pushed one by one: whole blocks, a shorter last one, and blocks that
    /// begin mid-buffer, which are refused (and then pushed one by one).
    #[test]
    fn long_run_rows_added_by_blocks_give_the_bits_of_one_by_one() {
        let (m, lags) = (5, 2);
        let z = |k: usize, i: usize| 1e2 * i as f64 + ((k * 7 + i * 3) as f64 * 0.37).sin();
        let mut one = LongRun::new(m, lags);
        for k in 0..150 {
            one.push_with(|row| row.iter_mut().enumerate().for_each(|(i, v)| *v = z(k, i)));
        }
        let mut blocks = LongRun::new(m, lags);
        // 3 alone, then blocks of 29 (refused mid-buffer, so one by one) up
        // to the buffer's end, then whole blocks and a last one of 22.
        let mut k = 0;
        for len in [3, 29, BLOCK, BLOCK, BLOCK, 22] {
            let added = blocks.push_rows_with(len, |rows, w| {
                for (s, row) in rows.chunks_exact_mut(w).enumerate() {
                    for (i, v) in row[..m].iter_mut().enumerate() {
                        *v += z(k + s, i);
                    }
                }
            });
            assert_eq!(added, len != 29, "a block of {len} from sample {k}");
            if !added {
                for s in k..k + len {
                    blocks.push_with(|row| {
                        row.iter_mut().enumerate().for_each(|(i, v)| *v = z(s, i))
                    });
                }
            }
            k += len;
        }
        assert_eq!(k, 150);
        assert_eq!(blocks.n, one.n);
        blocks.flush();
        one.flush();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&blocks.sums), bits(&one.sums));
        // Without a dimension there are no rows to lay out: refused.
        let mut empty = LongRun::new(0, lags);
        assert!(!empty.push_rows_with(4, |_, _| {}));
        assert_eq!(empty.n, 0);
    }

    /// Samples pushed a block at a time, slot-major, give the bits of the
    /// same samples pushed one by one: whole blocks, a shorter last one,
    /// blocks that begin mid-buffer (pushed one by one), keeping the rows
    /// or not.
    #[test]
    fn samples_pushed_by_blocks_give_the_bits_of_one_by_one() {
        let value = |k: usize, slot: usize, shift: f64| {
            1e3 * slot as f64 + ((k * 5 + slot) as f64 * 0.41 + shift).sin()
        };
        let cols = [0, 2, 3, 5];
        let (slots, samples) = (6, 203);
        let target = |k: usize| (k as f64 * 0.13).cos() * 7.0 + 2.0;
        let bits = |m: &CrossMoments| format!("{:?}", serde_json::to_string(m).ok());
        for keeping in [false, true] {
            for blocks in [vec![32; 6], vec![5, 27, 32, 32, 7, 25, 32, 32]] {
                let mut one = MomentAccumulator::new(4, 4);
                let mut by_blocks = MomentAccumulator::new(4, 4);
                if keeping {
                    one.keep_rows(samples, 0);
                    by_blocks.keep_rows(samples, 0);
                }
                let mut k0 = 0;
                for nb in blocks
                    .iter()
                    .copied()
                    .chain([samples - blocks.iter().sum::<usize>()])
                {
                    let block = |shift: f64| -> Vec<f64> {
                        (0..slots)
                            .flat_map(|c| (k0..k0 + nb).map(move |k| value(k, c, shift)))
                            .collect()
                    };
                    let (z, phi) = (block(0.5), block(0.0));
                    let t: Vec<f64> = (k0..k0 + nb).map(target).collect();
                    by_blocks.push_block(
                        SlotRows::new(&z, nb, (0, slots)),
                        SlotRows::new(&phi, nb, (0, slots)),
                        &cols,
                        &t,
                    );
                    for k in k0..k0 + nb {
                        let zk: Vec<f64> = (0..slots).map(|c| value(k, c, 0.5)).collect();
                        let pk: Vec<f64> = (0..slots).map(|c| value(k, c, 0.0)).collect();
                        one.push_columns(&zk[..], &pk[..], &cols, target(k));
                    }
                    k0 += nb;
                }
                let (one, one_rows) = one.finish_keeping();
                let (by_blocks, block_rows) = by_blocks.finish_keeping();
                assert_eq!(
                    bits(&one),
                    bits(&by_blocks),
                    "keeping {keeping}, {blocks:?}"
                );
                let rows = |r: Option<RegressorRows>| r.map(|r| format!("{:?}", r.rows));
                assert_eq!(rows(one_rows), rows(block_rows));
            }
        }
    }

    /// The regressor rows kept by one accumulation give a second one with
    /// other instruments exactly the sums it would compute itself, over a
    /// partial last block too (101 samples: three blocks and five rows).
    #[test]
    fn kept_regressor_rows_give_the_same_bits() {
        let dense = |k: usize, shift: f64| -> Vec<f64> {
            (0..6)
                .map(|i| 1e3 * (i as f64) + ((k * 5 + i) as f64 * 0.41 + shift).sin())
                .collect()
        };
        let cols = [0, 2, 3, 5];
        let target = |k: usize| (k as f64 * 0.13).cos() * 7.0 + 2.0;
        let mut first = MomentAccumulator::new(4, 4);
        first.keep_rows(101, 0);
        for k in 0..101 {
            first.push_columns(&dense(k, 0.5)[..], &dense(k, 0.0)[..], &cols, target(k));
        }
        let (sums_first, rows) = first.finish_keeping();
        let rows = rows.expect("rows kept");
        assert_eq!(rows.len(), 101);
        // Other instruments: computed in full, then against the kept rows.
        let mut full = MomentAccumulator::new(4, 4);
        let mut kept = MomentAccumulator::new(4, 4);
        for k in 0..101 {
            full.push_columns(&dense(k, 1.5)[..], &dense(k, 0.0)[..], &cols, target(k));
            kept.push_instruments(&dense(k, 1.5)[..], &cols, &rows);
        }
        let (full, kept) = (full.finish(), kept.finish_with(&rows));
        let bits = |m: &CrossMoments| format!("{:?}", serde_json::to_string(m).ok());
        assert_eq!(bits(&full), bits(&kept));
        // Without keeping, the first accumulation's sums are unchanged too.
        let mut plain = MomentAccumulator::new(4, 4);
        for k in 0..101 {
            plain.push_columns(&dense(k, 0.5)[..], &dense(k, 0.0)[..], &cols, target(k));
        }
        assert_eq!(bits(&plain.finish()), bits(&sums_first));
        // More instruments than kept rows: unusable sums, not wrong ones.
        let mut over = MomentAccumulator::new(4, 4);
        for k in 0..102 {
            over.push_instruments(&dense(k, 1.5)[..], &cols, &rows);
        }
        assert!(
            over.finish_with(&rows)
                .centred()
                .0
                .iter()
                .any(|v| v.is_nan())
        );
    }

    #[test]
    fn sums_resumed_after_a_prefix_give_the_same_bits() {
        let dense = |k: usize| -> Vec<f64> {
            (0..7)
                .map(|i| 1e2 * (i as f64) + ((k * 3 + i) as f64 * 0.37).sin())
                .collect()
        };
        let cols = [0, 1, 4, 5, 6];
        let target = |k: usize| (k as f64 * 0.21).cos() * 3.0 - 1.0;
        let bits = |m: &CrossMoments| format!("{:?}", serde_json::to_string(m).ok());
        // Prefixes ending inside a block, on a block's end, and before the first.
        for prefix in [5, 32, 77] {
            let mut whole = MomentAccumulator::new(5, 5);
            whole.keep_rows(200, 0);
            for k in 0..200 {
                whole.push_columns(&dense(k)[..], &dense(k + 1)[..], &cols, target(k));
            }
            let (whole, whole_rows) = whole.finish_keeping();
            let mut first = MomentAccumulator::new(5, 5);
            first.keep_rows(prefix, 200);
            for k in 0..prefix {
                first.push_columns(&dense(k)[..], &dense(k + 1)[..], &cols, target(k));
            }
            let partial = first.partial().expect("keeps its rows");
            let (_, rows) = first.finish_keeping();
            let rows = rows.expect("rows kept");
            assert!(partial.continues(&rows));
            let mut resumed = MomentAccumulator::new(5, 5);
            resumed.keep_rows_resuming(rows, partial, 200);
            for k in prefix..200 {
                resumed.push_columns(&dense(k)[..], &dense(k + 1)[..], &cols, target(k));
            }
            let (resumed, resumed_rows) = resumed.finish_keeping();
            assert_eq!(bits(&whole), bits(&resumed), "prefix {prefix}");
            let (a, b) = (whole_rows.expect("kept"), resumed_rows.expect("kept"));
            assert_eq!(format!("{:?}", a.rows), format!("{:?}", b.rows));
            assert_eq!(format!("{:?}", a.s_pp), format!("{:?}", b.s_pp));
        }
        // Sums of other rows, or of an accumulation that keeps none, do not continue.
        let mut other = MomentAccumulator::new(5, 5);
        other.keep_rows(10, 0);
        for k in 0..10 {
            other.push_columns(&dense(k)[..], &dense(k)[..], &cols, target(k));
        }
        let partial = other.partial().expect("keeps its rows");
        let mut longer = MomentAccumulator::new(5, 5);
        longer.keep_rows(11, 0);
        for k in 0..11 {
            longer.push_columns(&dense(k)[..], &dense(k)[..], &cols, target(k));
        }
        let (_, longer) = longer.finish_keeping();
        assert!(!partial.continues(&longer.expect("kept")));
        assert!(MomentAccumulator::new(5, 5).partial().is_none());
    }

    #[test]
    fn instrument_sums_resumed_against_kept_rows_give_the_same_bits() {
        let dense = |k: usize| -> Vec<f64> {
            (0..7)
                .map(|i| 1e2 * (i as f64) + ((k * 3 + i) as f64 * 0.37).sin())
                .collect()
        };
        let cols = [0, 1, 4, 5, 6];
        let target = |k: usize| (k as f64 * 0.21).cos() * 3.0 - 1.0;
        let bits = |m: &CrossMoments| format!("{:?}", serde_json::to_string(m).ok());
        // Instruments summed over the first samples go on over the rest of
        // the record's rows (a refinement's simulation continued), in a
        // keeping accumulation or against the kept rows.
        let mut rows_all = MomentAccumulator::new(5, 5);
        rows_all.keep_rows(200, 0);
        for k in 0..200 {
            rows_all.push_columns(&dense(k)[..], &dense(k + 1)[..], &cols, target(k));
        }
        let (_, rows_all) = rows_all.finish_keeping();
        let rows_all = rows_all.expect("rows kept");
        let z = |k: usize| dense(k + 7);
        let mut whole = MomentAccumulator::new(5, 5);
        for k in 0..200 {
            whole.push_instruments(&z(k)[..], &cols, &rows_all);
        }
        let whole = whole.finish_with(&rows_all);
        for prefix in [5, 32, 77] {
            let mut first = MomentAccumulator::new(5, 5);
            first.keep_rows(prefix, 0);
            for k in 0..prefix {
                first.push_columns(&dense(k)[..], &dense(k + 1)[..], &cols, target(k));
            }
            let (_, prefix_rows) = first.finish_keeping();
            let prefix_rows = prefix_rows.expect("rows kept");
            let mut over_kept = MomentAccumulator::new(5, 5);
            for k in 0..prefix {
                over_kept.push_instruments(&z(k)[..], &cols, &prefix_rows);
            }
            let from = over_kept.partial_instruments();
            assert!(from.continues_over(&rows_all) && from.continues(&prefix_rows));
            let mut resumed = MomentAccumulator::new(5, 5);
            resumed.resume_instruments(from.clone(), &rows_all);
            for k in prefix..200 {
                resumed.push_instruments(&z(k)[..], &cols, &rows_all);
            }
            assert_eq!(
                bits(&whole),
                bits(&resumed.finish_with(&rows_all)),
                "prefix {prefix}"
            );
            let mut scanning = MomentAccumulator::new(5, 5);
            scanning.keep_rows_resuming(prefix_rows, from, 200);
            for k in prefix..200 {
                scanning.push_columns(&z(k)[..], &dense(k + 1)[..], &cols, target(k));
            }
            let (scanned, _) = scanning.finish_keeping();
            assert_eq!(bits(&whole), bits(&scanned), "prefix {prefix}, scanning");
        }
    }
}
