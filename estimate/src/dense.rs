//! One equation's dense buffer (`n_out × n_cols` slots of regressors or
//! instruments) as the walk hands it to a sink: a slice of its own, or one
//! sample's column of a block the model evaluated slot-major
//! ([`BlockColumn`]). Sinks read either through [`Dense`], so the walk can
//! evaluate a block of equations at once and hand them over without
//! copying each back into a buffer of its own.

/// A dense equation buffer, read slot by slot.
pub trait Dense: Copy {
    /// Its number of slots.
    fn len(self) -> usize;
    /// Whether it has none.
    fn is_empty(self) -> bool {
        self.len() == 0
    }
    /// Slot `i`.
    fn at(self, i: usize) -> f64;
    /// Slots `from..from + len`, or none where the buffer is shorter.
    fn part(self, from: usize, len: usize) -> Self;
}

impl Dense for &[f64] {
    #[inline(always)]
    fn len(self) -> usize {
        <[f64]>::len(self)
    }
    #[inline(always)]
    fn at(self, i: usize) -> f64 {
        self[i]
    }
    #[inline(always)]
    fn part(self, from: usize, len: usize) -> Self {
        self.get(from..from + len).unwrap_or(&[])
    }
}

/// Sample `s` of a block of `n` samples evaluated slot-major (slot `k` of
/// sample `s` at `values[k · n + s]`): its slots `from..from + len`.
#[derive(Clone, Copy, Debug)]
pub struct BlockColumn<'a> {
    values: &'a [f64],
    n: usize,
    s: usize,
    from: usize,
    len: usize,
}

impl<'a> BlockColumn<'a> {
    /// Sample `s` of the block `values` of `n` samples of `slots` slots each.
    pub fn new(values: &'a [f64], n: usize, s: usize, slots: usize) -> BlockColumn<'a> {
        BlockColumn {
            values,
            n,
            s,
            from: 0,
            len: slots,
        }
    }
}

impl Dense for BlockColumn<'_> {
    #[inline(always)]
    fn len(self) -> usize {
        self.len
    }
    #[inline(always)]
    fn at(self, i: usize) -> f64 {
        self.values[(self.from + i) * self.n + self.s]
    }
    #[inline(always)]
    fn part(self, from: usize, len: usize) -> Self {
        let fits = from + len <= self.len;
        BlockColumn {
            from: self.from + from,
            len: if fits { len } else { 0 },
            ..self
        }
    }
}

/// The equations of a block as the walk evaluated them: regressors `phi`
/// and instruments `z` slot-major (`slots × n`; `z` is `phi` where the
/// regressors are their own instruments) and targets `t`, `n_out` per
/// equation. A sink reads each equation's column ([`EquationBlock::equation`])
/// or a slot across the block, contiguous, to vectorise over samples.
#[derive(Clone, Copy, Debug)]
pub struct EquationBlock<'a> {
    /// The regressors, slot-major.
    pub phi: &'a [f64],
    /// The instruments, slot-major.
    pub z: &'a [f64],
    /// The targets, equation after equation.
    pub t: &'a [f64],
    /// Equations in the block.
    pub n: usize,
    /// Slots of an equation (`n_out × n_cols`).
    pub slots: usize,
    /// Targets of an equation.
    pub n_out: usize,
}

impl<'a> EquationBlock<'a> {
    /// Equation `s`: its instruments, regressors and targets.
    #[inline(always)]
    pub fn equation(&self, s: usize) -> (BlockColumn<'a>, BlockColumn<'a>, &'a [f64]) {
        (
            BlockColumn::new(self.z, self.n, s, self.slots),
            BlockColumn::new(self.phi, self.n, s, self.slots),
            &self.t[s * self.n_out..(s + 1) * self.n_out],
        )
    }
}

/// Slots `from..from + len` of a block of `n` samples evaluated
/// slot-major (`values`, `slots × n`), each a row of the block's samples.
#[derive(Clone, Copy, Debug)]
pub struct SlotRows<'a> {
    values: &'a [f64],
    n: usize,
    from: usize,
    len: usize,
}

impl<'a> SlotRows<'a> {
    /// Slots `from..from + len` of the block `values` of `n` samples.
    pub fn new(values: &'a [f64], n: usize, (from, len): (usize, usize)) -> SlotRows<'a> {
        SlotRows {
            values,
            n,
            from,
            len,
        }
    }
    /// Slot `i` (from `from`) of every sample.
    #[inline(always)]
    pub fn row(&self, i: usize) -> &'a [f64] {
        &self.values[(self.from + i) * self.n..][..self.n]
    }
    /// Sample `s`'s slots, as [`EquationBlock::equation`] gives them, then
    /// [`Dense::part`].
    #[inline(always)]
    pub fn column(&self, s: usize) -> BlockColumn<'a> {
        let slots = self.values.len() / self.n.max(1);
        BlockColumn::new(self.values, self.n, s, slots).part(self.from, self.len)
    }
}
