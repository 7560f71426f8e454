//! The study engine every Monte Carlo campaign of leeway runs on: the
//! paper's study (`leeway reproduce`) and a trial design's verification
//! (`leeway design --verify`); the zigzag campaign takes its seeds. Runs are independent
//! and seeded by their index ([`keyed_seed`]), computed in parallel
//! (rayon) and returned in run order, so results do not depend on the
//! thread count; a cluster (Dask) runs the same per-run functions and
//! merges them in the same order.

use rayon::prelude::*;

/// Runs `run(0..runs)` in parallel, calling `progress` after each, and
/// returns the results in run order.
pub fn campaign<T: Send>(
    runs: usize,
    progress: &(dyn Fn() + Sync),
    run: &(dyn Fn(usize) -> T + Sync),
) -> Vec<T> {
    (0..runs)
        .into_par_iter()
        .map(|r| {
            let out = run(r);
            progress();
            out
        })
        .collect()
}

/// The seed of run `run` of a set named `name`: FNV-1a of the name, then
/// SplitMix64 of the three numbers (shared by every seeded campaign).
pub fn keyed_seed(seed: u64, name: &str, run: usize) -> u64 {
    let key = name.bytes().fold(0xCBF2_9CE4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01B3)
    });
    let mut z = seed
        ^ key.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (run as u64).wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_campaign_returns_runs_in_order_at_any_thread_count() {
        let square = |r: usize| keyed_seed(7, "test", r) % 1000;
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a one-thread pool");
        let a = one.install(|| campaign(50, &|| (), &square));
        let b = campaign(50, &|| (), &square);
        assert_eq!(a, b);
        assert_eq!(a, (0..50).map(square).collect::<Vec<_>>());
    }
}
