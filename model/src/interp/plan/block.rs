//! The regressor plans evaluated for a block of samples at once: the table
//! holds a row of `n` values per entry (`t[v·n + s]` for sample `s`), and
//! each product is a loop over the samples of its rows. The plan's
//! bookkeeping — which values a product multiplies, where it goes — is read
//! once per block instead of once per sample, and the loops over samples
//! run on contiguous rows, which the compiler vectorises. Every value is
//! computed operation for operation as in the per-sample evaluation, so the
//! two agree bit for bit.

use super::{General, Product, Products, RegressorPlan, Table, TableShare};
use crate::model::Signals;
use std::cell::RefCell;

thread_local! {
    /// The block table, one per thread, grown once to the largest block.
    static BLOCK_TABLE: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

/// The row of value `v` in a block table of `n` samples.
#[inline(always)]
fn row(t: &[f64], v: u32, n: usize) -> &[f64] {
    &t[v as usize * n..][..n]
}

#[inline(always)]
fn row_mut(t: &mut [f64], v: u32, n: usize) -> &mut [f64] {
    &mut t[v as usize * n..][..n]
}

impl TableShare {
    /// The share of sample `s`: `R_lk·d`, `−(R_lk·d)` or `d`.
    #[inline(always)]
    fn value_at(&self, t: &[f64], n: usize, s: usize, disturbances: &[f64]) -> f64 {
        use leeway_structure::ir::Share;
        let d = disturbances[self.component as usize];
        match self.share {
            Share::Rot(_) => t[self.rot as usize * n + s] * d,
            Share::NegRot(_) => -(t[self.rot as usize * n + s] * d),
            Share::One => d,
        }
    }
}

impl Table {
    /// Fills a block table: the signals of every sample, then the derived
    /// values row by row. `signs` holds `n_signs` values per sample.
    fn fill_block(&self, samples: &[Signals], signs: &[f64], n_signs: usize, t: &mut [f64]) {
        let n = samples.len();
        let [x, u, rot, n_s] = self.copy;
        for (s, sig) in samples.iter().enumerate() {
            for (i, &v) in sig.states[..x].iter().enumerate() {
                t[i * n + s] = v;
            }
            for (i, &v) in sig.inputs[..u].iter().enumerate() {
                t[(self.inputs_at + i) * n + s] = v;
            }
            for (i, &v) in sig.rotation[..rot].iter().enumerate() {
                t[(self.rotation_at + i) * n + s] = v;
            }
            for (i, &v) in signs[s * n_signs..][..n_s].iter().enumerate() {
                t[(self.signs_at + i) * n + s] = v;
            }
        }
        for a in &self.disturbed_once {
            for (s, sig) in samples.iter().enumerate() {
                let v = t[a.base as usize * n + s] - a.shares.value_at(t, n, s, sig.disturbances);
                t[a.value as usize * n + s] = v;
            }
        }
        for a in &self.disturbed_twice {
            let [p0, p1] = a.shares;
            for (s, sig) in samples.iter().enumerate() {
                let d = sig.disturbances;
                let v = t[a.base as usize * n + s]
                    - (p0.value_at(t, n, s, d) + p1.value_at(t, n, s, d));
                t[a.value as usize * n + s] = v;
            }
        }
        for a in &self.disturbed {
            let (start, end) = a.shares;
            let shares = &self.shares[start as usize..end as usize];
            for (s, sig) in samples.iter().enumerate() {
                let mut sum = 0.0;
                for (k, sh) in shares.iter().enumerate() {
                    let p = sh.value_at(t, n, s, sig.disturbances);
                    sum = if k == 0 { p } else { sum + p };
                }
                let v = t[a.base as usize * n + s] - sum;
                t[a.value as usize * n + s] = v;
            }
        }
        for &(value, of) in &self.moduli {
            // `value` comes after `of`: split there to read one row and
            // write the other.
            let (lo, hi) = t.split_at_mut(value as usize * n);
            for (m, &v) in hi[..n].iter_mut().zip(row(lo, of, n)) {
                *m = v.abs();
            }
        }
    }
}

impl<const A: usize> Product<A> {
    /// `dest[s] = ((k · r0[s]) · r1[s]) · …` for every sample.
    #[inline(always)]
    fn write_rows(&self, t: &[f64], n: usize, dest: &mut [f64]) {
        // Rows cut to `dest`'s length, so the loop needs no bounds check
        // and vectorises.
        let rows: [&[f64]; A] = std::array::from_fn(|i| &row(t, self.factors[i], n)[..dest.len()]);
        for (s, d) in dest.iter_mut().enumerate() {
            let mut v = self.coefficient;
            for r in &rows {
                v *= r[s];
            }
            *d = v;
        }
    }
}

impl General {
    #[inline]
    fn write_rows(&self, factors: &[u32], t: &[f64], n: usize, dest: &mut [f64]) {
        for (s, d) in dest.iter_mut().enumerate() {
            let mut v = self.coefficient;
            for &f in &factors[self.start as usize..self.end as usize] {
                v *= t[f as usize * n + s];
            }
            *d = v;
        }
    }
}

impl Products {
    /// Every product's row of `n` samples into `dest` (rows by `at`).
    #[inline(always)]
    fn write_block(&self, t: &[f64], n: usize, dest: &mut [f64]) {
        for p in &self.constant {
            row_mut(dest, p.at, n).fill(p.coefficient);
        }
        for p in &self.one {
            p.write_rows(t, n, row_mut(dest, p.at, n));
        }
        for p in &self.two {
            p.write_rows(t, n, row_mut(dest, p.at, n));
        }
        for p in &self.three {
            p.write_rows(t, n, row_mut(dest, p.at, n));
        }
        for (at, p) in &self.general {
            p.write_rows(&self.factors, t, n, row_mut(dest, *at, n));
        }
    }
}

impl RegressorPlan {
    /// The regressors of a block of samples, slot-major: slot `k` of sample
    /// `s` at `out[k·n + s]`; every slot of `out[..len·n]` written. `signs`
    /// holds `n_signs` values per sample (none for the basic predictor).
    pub(in crate::interp) fn eval_block(
        &self,
        samples: &[Signals],
        signs: &[f64],
        n_signs: usize,
        out: &mut [f64],
    ) {
        self.eval_block_in(samples, signs, n_signs, out, true);
    }

    /// [`RegressorPlan::eval_block`] without writing the slots the plan
    /// leaves zero (structurally, or not wanted): they keep what `out` holds.
    pub(in crate::interp) fn eval_block_nonzero(
        &self,
        samples: &[Signals],
        signs: &[f64],
        n_signs: usize,
        out: &mut [f64],
    ) {
        self.eval_block_in(samples, signs, n_signs, out, false);
    }

    #[inline(always)]
    fn eval_block_in(
        &self,
        samples: &[Signals],
        signs: &[f64],
        n_signs: usize,
        out: &mut [f64],
        zeros: bool,
    ) {
        let n = samples.len();
        let out = &mut out[..self.len * n];
        BLOCK_TABLE.with(|cell| {
            // Nothing here re-enters the cell.
            let mut t = cell.borrow_mut();
            let len = self.table.len * n;
            if t.len() < len {
                t.resize(len, 0.0);
            }
            let t = &mut t[..len];
            self.table.fill_block(samples, signs, n_signs, t);
            let (t, e) = t.split_at_mut(self.entries_at * n);
            let t: &[f64] = t;
            self.entries.write_block(t, n, e);
            let e: &[f64] = e;
            if zeros {
                for &(start, end) in &self.zeros {
                    out[start as usize * n..end as usize * n].fill(0.0);
                }
            }
            self.slots.write_block(t, n, out);
            for &(slot, a, b) in &self.pairs {
                let (ra, rb) = (row(e, a, n), row(e, b, n));
                for ((o, x), y) in row_mut(out, slot, n).iter_mut().zip(ra).zip(rb) {
                    *o = x + y;
                }
            }
            for &(slot, start, end) in &self.sums {
                let summands = &self.summands[start as usize..end as usize];
                for (s, o) in row_mut(out, slot, n).iter_mut().enumerate() {
                    let mut acc = 0.0;
                    for (k, &i) in summands.iter().enumerate() {
                        let v = e[i as usize * n + s];
                        acc = if k == 0 { v } else { acc + v };
                    }
                    *o = acc;
                }
            }
        });
    }
}
