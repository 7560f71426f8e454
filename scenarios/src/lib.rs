//! leeway-scenarios: data leeway makes up, seeded and reproducible at any
//! thread count. Synthetic experiments from a true system ([`synth`]), a
//! noisy simulation on a recorded input ([`noisy`]), the paper's Monte
//! Carlo study ([`study`]), a tanker zigzag campaign
//! ([`zigzag`]) and the checks of an input design on the true trajectory
//! ([`design`]), all on one Monte Carlo engine ([`engine`]). With
//! leeway-design, which plans trials on it, the only library crates of the
//! workspace that use random numbers (rand, rand_chacha, rand_distr) and
//! threads (rayon).

pub mod design;
pub mod engine;
pub mod ferry;
pub mod noisy;
pub mod raw_ferry;
pub mod study;
pub mod synth;
pub mod zigzag;
