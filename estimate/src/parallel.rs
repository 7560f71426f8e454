//! Streamed experiments' passes on every core: each experiment is walked
//! on one thread, whole, as on one core, and the summaries come back in
//! experiment order, so the driver combines the same numbers in the same
//! order whatever the number of threads.

use std::sync::atomic::{AtomicUsize, Ordering};

/// The threads a pass over `n` experiments uses: the machine's cores
/// (`std::thread::available_parallelism`), at most one per experiment.
pub fn threads_for(n: usize) -> usize {
    std::thread::available_parallelism()
        .map_or(1, std::num::NonZeroUsize::get)
        .min(n)
        .max(1)
}

/// `f(i)` for every `i` in `0..n`, on `threads` threads taking the next
/// index as they finish one, returned in index order. A panic in `f` is
/// resumed here.
pub fn in_order<T: Send>(n: usize, threads: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    if threads <= 1 || n <= 1 {
        return (0..n).map(f).collect();
    }
    let next = AtomicUsize::new(0);
    let mut done: Vec<(usize, T)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads.min(n))
            .map(|_| {
                s.spawn(|| {
                    let mut mine = Vec::new();
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        if i >= n {
                            return mine;
                        }
                        mine.push((i, f(i)));
                    }
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap_or_else(|p| std::panic::resume_unwind(p)))
            .collect()
    });
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, t)| t).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn results_come_back_in_order_whatever_the_threads() {
        let square = |i: usize| i * i;
        let one = in_order(37, 1, square);
        for threads in [2, 3, 8, 64] {
            assert_eq!(in_order(37, threads, square), one);
        }
        assert_eq!(in_order(0, 4, square), Vec::<usize>::new());
    }
}
