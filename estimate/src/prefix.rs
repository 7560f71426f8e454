//! Prefix reuse: what a moment pass over an in-memory record takes up from
//! the passes over a shorter record it begins with (the study's growing
//! prefixes, kept by [`RecordCache::with_prefix`]), and from which equation
//! it goes on.
//!
//! A [`Checkpoint`] is what such earlier passes left: the regressor rows of
//! the first equations, where a θ-free pass stood after them ([`Resume`]),
//! or where a pass that simulated the same instruments stood
//! ([`SimResume`], with the simulation's states). Every check here guards
//! the bits: a checkpoint that does not fit the pass exactly is dropped,
//! and the pass then sums from the first sample, as without a prefix.

use crate::cache::{InstrumentsKey, RecordCache, Resume, SimResume, SimulationKey};
use crate::moments::{PartialSums, RegressorRows};
use crate::protocol::PassPlan;
use crate::record::ExperimentInfo;
use crate::walk::{History, SimWalk};

/// What a moment pass could take up, as its runner sees it.
pub(super) struct Wanted<'a> {
    pub(super) plan: &'a PassPlan,
    pub(super) info: &'a ExperimentInfo,
    /// Samples of the pass's record.
    pub(super) samples: usize,
    /// The model's states (outputs).
    pub(super) n_out: usize,
    /// The pass keeps its regressor rows (a scanning pass): it may begin
    /// with the prefix's rows.
    pub(super) keeps_rows: bool,
    /// What its instruments are, if they do not depend on θ.
    pub(super) instruments: Option<&'a InstrumentsKey>,
    /// The record's heading rotations are kept, every sample's.
    pub(super) headings_known: bool,
    /// A warm start's first pass (simulated instruments, no reference
    /// simulation): the simulation it continues, over how many samples.
    pub(super) simulation: Option<(SimulationKey<'a>, usize)>,
}

impl Wanted<'_> {
    /// Equations of the pass's record.
    fn equations(&self) -> usize {
        self.samples.saturating_sub(2)
    }
}

/// What a moment pass takes up from the passes over a prefix of its record
/// (nothing, by default).
#[derive(Default)]
pub(super) struct Checkpoint {
    /// The regressor rows of the record's first equations, per output.
    rows: Option<Vec<RegressorRows>>,
    /// Where the θ-free pass that kept `rows` stood after them.
    resume: Option<Resume>,
    /// Where a pass that simulated the same instruments stood.
    simulation: Option<SimResume>,
    /// That simulation's states after each step (until taken).
    states: Option<Vec<f64>>,
}

/// A [`Checkpoint`] taken apart for the walk and the accumulators.
pub(super) struct Resumption {
    /// Kept rows of the first equations, per output: the walk skips their
    /// measured side, the accumulators begin with them.
    pub(super) rows: Option<Vec<RegressorRows>>,
    /// Where the accumulation over `rows` stood, per output: the
    /// accumulators go on from there.
    pub(super) sums: Option<Vec<PartialSums>>,
    /// Where a simulation's instruments stood against the whole record's
    /// kept rows (no prefix rows), per output.
    pub(super) sums_over_kept: Option<Vec<PartialSums>>,
    /// Where a θ-free walk stood.
    pub(super) history: Option<History>,
    /// Where a simulating walk stood.
    pub(super) simulation: Option<SimWalk>,
}

impl Checkpoint {
    /// Takes from `cache` what a pass `wanted` can go on from (what is
    /// taken is given back to `budget`, used or not).
    pub(super) fn take(cache: &mut RecordCache, budget: &mut usize, wanted: &Wanted) -> Checkpoint {
        let (plan, info) = (wanted.plan, wanted.info);
        // Rows kept over a shorter prefix of the record are the scanning
        // pass's first rows, unless the whole record's are kept already.
        let rows = if wanted.keeps_rows && cache.regressors(plan, info).is_none() {
            cache.take_prefix(plan, info, budget)
        } else {
            None
        }
        .filter(|(rows, _)| rows_fit(rows, plan.cols.len(), wanted.equations()));
        // A pass whose instruments do not depend on θ goes on from where the
        // pass that kept the prefix's rows stood, if it had these instruments.
        let (rows, resume) = match rows {
            Some((rows, resume)) => {
                let resume = resume
                    .filter(|r| resume_fits(r, &rows, wanted.instruments, wanted.headings_known));
                (Some(rows), resume)
            }
            None => (None, None),
        };
        // A warm start's first pass goes on from where the pass over the
        // shorter record that simulated the same instruments stood.
        let simulation = match &wanted.simulation {
            Some((key, samples)) if resume.is_none() && wanted.headings_known => {
                cache.take_prefix_simulation(plan, info, key, *samples, budget)
            }
            _ => None,
        }
        .filter(|(s, _)| s.walk.fits(wanted.samples, wanted.n_out))
        // It needs the regressor rows of its first samples: the prefix's, or
        // the whole record's kept by another pass.
        .filter(|(s, _)| match &rows {
            Some(rows) => simulation_continues_rows(&s.walk, &s.sums, rows),
            None => {
                plan.instruments.is_some()
                    && cache.regressors(plan, info).is_some_and(|kept| {
                        simulation_continues_kept(&s.walk, &s.sums, kept, wanted.equations())
                    })
            }
        });
        let (simulation, states) = simulation.unzip();
        Checkpoint {
            rows,
            resume,
            simulation,
            states,
        }
    }

    /// Equations whose regressors and targets the taken rows hold.
    pub(super) fn measured_known(&self) -> usize {
        self.rows.as_ref().map_or(0, |p| p[0].len())
    }

    /// Equations already summed: the pass goes on with the next one.
    pub(super) fn resumed_equations(&self) -> usize {
        self.resume
            .as_ref()
            .map(|r| r.history.equations)
            .or(self.simulation.as_ref().map(|s| s.walk.equations))
            .unwrap_or(0)
    }

    /// The prefix's heading rotations (taken from `cache`) for a pass that
    /// goes on from a θ-free pass and keeps its own: those of the samples
    /// it goes on after, or none.
    pub(super) fn take_headings(&self, cache: &mut RecordCache) -> Option<Vec<[f64; 2]>> {
        let resume = self.resume.as_ref()?;
        cache
            .take_prefix_headings()
            .filter(|h| h.len() == resume.history.samples)
    }

    /// The simulation's states after each step so far (taken), if the pass
    /// goes on from a simulation: the trajectory it keeps goes on from them.
    pub(super) fn take_states(&mut self) -> Option<Vec<f64>> {
        self.states.take()
    }

    /// Whether the pass goes on from a θ-free pass.
    pub(super) fn resumes(&self) -> bool {
        self.resume.is_some()
    }

    /// The pieces the walk and the accumulators go on from.
    pub(super) fn into_resumption(self) -> Resumption {
        let (simulation, sim_sums) = match self.simulation {
            Some(s) => (Some(s.walk), Some(s.sums)),
            None => (None, None),
        };
        let (history, resume_sums) = match self.resume {
            Some(r) => (Some(r.history), Some(r.sums)),
            None => (None, None),
        };
        // A simulation resumed over kept rows of the whole record goes on
        // from its instruments' sums; one over the prefix's rows, as a
        // θ-free pass does, from its rows' too.
        let (sums, sums_over_kept) = match (resume_sums, sim_sums) {
            (Some(s), _) => (Some(s), None),
            (None, Some(s)) if self.rows.is_some() => (Some(s), None),
            (None, s) => (None, s),
        };
        Resumption {
            rows: self.rows,
            sums,
            sums_over_kept,
            history,
            simulation,
        }
    }
}

/// Whether `rows`, kept over a prefix, can begin a pass with `outputs`
/// outputs over `equations` equations: one set per output, of one length,
/// not empty and no longer than the record.
pub(super) fn rows_fit(rows: &[RegressorRows], outputs: usize, equations: usize) -> bool {
    rows.len() == outputs
        && rows
            .iter()
            .all(|r| r.len() == rows[0].len() && !r.is_empty() && r.len() <= equations)
}

/// Whether a θ-free pass with `instruments` can go on from `resume` over
/// `rows`: the same instruments, heading rotations to go on with, and a
/// walk and sums that stood exactly after the rows' samples.
pub(super) fn resume_fits(
    resume: &Resume,
    rows: &[RegressorRows],
    instruments: Option<&InstrumentsKey>,
    headings_known: bool,
) -> bool {
    let r = resume;
    instruments == Some(&r.instruments)
        && (r.history.continues_headings() || headings_known)
        && r.history.equations == rows[0].len()
        && r.history.samples == rows[0].len() + 2
        && r.sums.len() == rows.len()
        && r.sums.iter().zip(rows).all(|(s, k)| s.continues(k))
}

/// Whether a simulation that stood at `walk` with `sums` goes on over the
/// prefix's `rows`: as many equations, and sums over exactly those rows.
pub(super) fn simulation_continues_rows(
    walk: &SimWalk,
    sums: &[PartialSums],
    rows: &[RegressorRows],
) -> bool {
    rows[0].len() == walk.equations
        && sums.len() == rows.len()
        && sums.iter().zip(rows).all(|(p, r)| p.continues(r))
}

/// Whether a simulation that stood at `walk` with `sums` goes on against
/// `kept`, the whole record's rows (`equations` each).
pub(super) fn simulation_continues_kept(
    walk: &SimWalk,
    sums: &[PartialSums],
    kept: &[RegressorRows],
    equations: usize,
) -> bool {
    kept.len() == sums.len()
        && kept
            .iter()
            .zip(sums)
            .all(|(r, p)| r.len() == equations && p.len() == walk.equations && p.continues_over(r))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cache::Kept;
    use crate::method::Instruments;
    use crate::moments::MomentAccumulator;
    use leeway_structure::ir::PredictorKind;

    fn plan(instruments: Option<Instruments>) -> PassPlan {
        PassPlan {
            kind: PredictorKind::Measured,
            instruments,
            delayed_mean: false,
            n_cols: 2,
            cols: vec![vec![0, 1]],
            held: Vec::new(),
        }
    }

    fn info() -> ExperimentInfo {
        ExperimentInfo {
            signs: Vec::new(),
            varying: Vec::new(),
            fixed_sign_columns: Vec::new(),
            measured_mean: Vec::new(),
            bound: Vec::new(),
            spread: 0.0,
            frozen: None,
        }
    }

    fn row(k: usize) -> [f64; 2] {
        [k as f64 * 0.5, 1.0 / (k + 1) as f64]
    }

    /// The rows of one output's first `equations` equations, and where
    /// their (keeping) accumulation stood.
    fn rows(equations: usize) -> (RegressorRows, PartialSums) {
        let mut a = MomentAccumulator::new(2, 2);
        a.keep_rows(equations, 0);
        for k in 0..equations {
            a.push_columns(&row(k)[..], &row(k)[..], &[0, 1], k as f64);
        }
        let partial = a.partial().expect("keeps its rows");
        let (_, rows) = a.finish_keeping();
        (rows.expect("kept"), partial)
    }

    fn least_squares() -> InstrumentsKey {
        InstrumentsKey {
            instruments: None,
            means: Vec::new(),
        }
    }

    /// The cache of a longer record that begins with a record over which
    /// a pass kept `kept` (with `plan`), and the budget left.
    fn continued(plan: &PassPlan, kept: Kept) -> (RecordCache, usize) {
        let mut first = RecordCache::default();
        let mut budget = 1 << 20;
        first.keep(plan, &info(), kept, &mut budget);
        let mut budget = 1 << 20;
        let cache = RecordCache::with_prefix(first.into_continued(), &mut budget);
        (cache, budget)
    }

    /// What a least-squares pass over 10 equations (12 samples) keeps:
    /// its rows, and where it stood (its heading state kept or not).
    fn least_squares_prefix(headings: bool) -> Kept<'static> {
        let (rows, partial) = rows(10);
        Kept {
            regressors: Some(vec![rows]),
            resume: Some(Resume {
                instruments: least_squares(),
                history: History::after(12, 10, headings),
                sums: vec![partial],
            }),
            headings: None,
            trajectory: None,
            simulation: None,
        }
    }

    fn wanted<'a>(
        plan: &'a PassPlan,
        info: &'a ExperimentInfo,
        instruments: Option<&'a InstrumentsKey>,
        samples: usize,
    ) -> Wanted<'a> {
        Wanted {
            plan,
            info,
            samples,
            n_out: 1,
            keeps_rows: true,
            instruments,
            headings_known: false,
            simulation: None,
        }
    }

    #[test]
    fn a_scanning_pass_takes_the_prefix_rows_and_goes_on_after_them() {
        let (plan, info, key) = (plan(None), info(), least_squares());
        let (mut cache, before) = continued(&plan, least_squares_prefix(true));
        let mut budget = before;
        let wanted = wanted(&plan, &info, Some(&key), 30);
        let taken = Checkpoint::take(&mut cache, &mut budget, &wanted);
        assert_eq!(taken.measured_known(), 10);
        assert_eq!(taken.resumed_equations(), 10);
        assert!(taken.resumes());
        // The rows' room is given back: the pass keeps the whole record's.
        assert!(budget > before);
        let from = taken.into_resumption();
        assert!(from.rows.is_some() && from.sums.is_some() && from.history.is_some());
        assert!(from.sums_over_kept.is_none() && from.simulation.is_none());
        // Taken: a second pass finds nothing.
        let again = Checkpoint::take(&mut cache, &mut budget, &wanted);
        assert_eq!((again.measured_known(), again.resumed_equations()), (0, 0));
    }

    #[test]
    fn other_instruments_take_the_rows_but_sum_from_the_first_equation() {
        let (plan, info) = (plan(Some(Instruments::Delayed)), info());
        let delayed = InstrumentsKey {
            instruments: Some(Instruments::Delayed),
            means: Vec::new(),
        };
        let (mut cache, mut budget) = continued(&plan, least_squares_prefix(true));
        let wanted = wanted(&plan, &info, Some(&delayed), 30);
        let taken = Checkpoint::take(&mut cache, &mut budget, &wanted);
        assert_eq!(taken.measured_known(), 10);
        assert_eq!(taken.resumed_equations(), 0);
        assert!(!taken.resumes());
        let from = taken.into_resumption();
        assert!(from.rows.is_some() && from.sums.is_none() && from.history.is_none());
    }

    #[test]
    fn a_pass_that_keeps_no_rows_leaves_them_for_one_that_does() {
        let (plan, info, key) = (plan(None), info(), least_squares());
        let (mut cache, mut budget) = continued(&plan, least_squares_prefix(true));
        let mut not_scanning = wanted(&plan, &info, Some(&key), 30);
        not_scanning.keeps_rows = false;
        let taken = Checkpoint::take(&mut cache, &mut budget, &not_scanning);
        assert_eq!((taken.measured_known(), taken.resumed_equations()), (0, 0));
        let scanning = wanted(&plan, &info, Some(&key), 30);
        let taken = Checkpoint::take(&mut cache, &mut budget, &scanning);
        assert_eq!(
            (taken.measured_known(), taken.resumed_equations()),
            (10, 10)
        );
    }

    #[test]
    fn rows_longer_than_the_record_are_dropped() {
        let (plan, info, key) = (plan(None), info(), least_squares());
        let (mut cache, mut budget) = continued(&plan, least_squares_prefix(true));
        // 11 samples: 9 equations, fewer than the 10 rows kept.
        let taken = Checkpoint::take(
            &mut cache,
            &mut budget,
            &wanted(&plan, &info, Some(&key), 11),
        );
        assert_eq!((taken.measured_known(), taken.resumed_equations()), (0, 0));
        // Exactly as long: taken.
        let (mut cache, mut budget) = continued(&plan, least_squares_prefix(true));
        let taken = Checkpoint::take(
            &mut cache,
            &mut budget,
            &wanted(&plan, &info, Some(&key), 12),
        );
        assert_eq!(
            (taken.measured_known(), taken.resumed_equations()),
            (10, 10)
        );
    }

    #[test]
    fn a_walk_without_its_heading_state_goes_on_only_over_kept_headings() {
        let (plan, info, key) = (plan(None), info(), least_squares());
        let (mut cache, mut budget) = continued(&plan, least_squares_prefix(false));
        let taken = Checkpoint::take(
            &mut cache,
            &mut budget,
            &wanted(&plan, &info, Some(&key), 30),
        );
        assert_eq!((taken.measured_known(), taken.resumed_equations()), (10, 0));
        let (mut cache, mut budget) = continued(&plan, least_squares_prefix(false));
        let mut known = wanted(&plan, &info, Some(&key), 30);
        known.headings_known = true;
        let taken = Checkpoint::take(&mut cache, &mut budget, &known);
        assert_eq!(
            (taken.measured_known(), taken.resumed_equations()),
            (10, 10)
        );
    }

    #[test]
    fn decisions_on_rows_and_sums() {
        let (ten, partial) = rows(10);
        let (nine, _) = rows(9);
        assert!(rows_fit(std::slice::from_ref(&ten), 1, 10));
        assert!(
            !rows_fit(std::slice::from_ref(&ten), 1, 9),
            "longer than the record"
        );
        assert!(
            !rows_fit(std::slice::from_ref(&ten), 2, 10),
            "one set per output"
        );
        assert!(
            !rows_fit(&[ten.clone(), nine.clone()], 2, 10),
            "of one length"
        );
        let resume = Resume {
            instruments: least_squares(),
            history: History::after(12, 10, true),
            sums: vec![partial.clone()],
        };
        let key = least_squares();
        assert!(resume_fits(
            &resume,
            std::slice::from_ref(&ten),
            Some(&key),
            false
        ));
        assert!(!resume_fits(
            &resume,
            std::slice::from_ref(&ten),
            None,
            false
        ));
        assert!(!resume_fits(
            &resume,
            std::slice::from_ref(&nine),
            Some(&key),
            false
        ));
        let walk = SimWalk::after(12, 10, 1);
        let sums = std::slice::from_ref(&partial);
        assert!(simulation_continues_rows(
            &walk,
            sums,
            std::slice::from_ref(&ten)
        ));
        assert!(!simulation_continues_rows(
            &walk,
            sums,
            std::slice::from_ref(&nine)
        ));
        // Against the whole record's rows: instruments summed over the first ten.
        let (whole, _) = rows(28);
        let mut over = MomentAccumulator::new(2, 2);
        for k in 0..10 {
            over.push_instruments(&row(k)[..], &[0, 1], &whole);
        }
        let over = [over.partial_instruments()];
        let whole = std::slice::from_ref(&whole);
        assert!(simulation_continues_kept(&walk, &over, whole, 28));
        assert!(
            !simulation_continues_kept(&walk, &over, whole, 29),
            "other record"
        );
        let walk11 = SimWalk::after(13, 11, 1);
        assert!(
            !simulation_continues_kept(&walk11, &over, whole, 28),
            "other walk"
        );
    }

    #[test]
    fn a_warm_start_goes_on_from_the_prefix_simulation_over_its_rows() {
        let (plan, info) = (plan(Some(Instruments::Simulated)), info());
        let (theta, mu) = ([0.5, -2.0], [0.1]);
        let prefix = || {
            let (rows, partial) = rows(10);
            let walk = SimWalk::after(12, 10, 1);
            let states = vec![0.0; walk.trajectory_len()];
            let key = SimulationKey {
                theta: &theta,
                mu: &mu,
                means: Vec::new(),
            };
            Kept {
                regressors: Some(vec![rows]),
                resume: None,
                headings: None,
                trajectory: Some((&theta, &mu, states)),
                simulation: Some((key, walk, vec![partial])),
            }
        };
        let warm = |samples: usize, headings_known: bool| Wanted {
            plan: &plan,
            info: &info,
            samples: 30,
            n_out: 1,
            keeps_rows: true,
            instruments: None,
            headings_known,
            simulation: Some((
                SimulationKey {
                    theta: &theta,
                    mu: &mu,
                    means: Vec::new(),
                },
                samples,
            )),
        };
        let (mut cache, mut budget) = continued(&plan, prefix());
        let mut taken = Checkpoint::take(&mut cache, &mut budget, &warm(12, true));
        assert_eq!(
            (taken.measured_known(), taken.resumed_equations()),
            (10, 10)
        );
        assert_eq!(taken.take_states().map(|s| s.len()), Some(11));
        let from = taken.into_resumption();
        assert!(from.simulation.is_some() && from.sums.is_some());
        assert!(from.history.is_none() && from.sums_over_kept.is_none());
        // Without the record's heading rotations, or over other samples, not.
        for (samples, known) in [(12, false), (13, true)] {
            let (mut cache, mut budget) = continued(&plan, prefix());
            let taken = Checkpoint::take(&mut cache, &mut budget, &warm(samples, known));
            assert_eq!((taken.measured_known(), taken.resumed_equations()), (10, 0));
        }
        // Another θ simulated: not.
        let other = [0.5, -2.5];
        let (mut cache, mut budget) = continued(&plan, prefix());
        let mut wanted = warm(12, true);
        wanted.simulation = Some((
            SimulationKey {
                theta: &other,
                mu: &mu,
                means: Vec::new(),
            },
            12,
        ));
        let taken = Checkpoint::take(&mut cache, &mut budget, &wanted);
        assert_eq!(taken.resumed_equations(), 0);
    }
}
