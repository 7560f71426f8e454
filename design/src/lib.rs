//! leeway-design: planning the trial for a new craft (paper A1, A7, A12,
//! A13, Remarks 1–2). From the exact analysis's smallest set of sign
//! patterns and a plan file ([`plan`]: what the engineer knows before the
//! trial), [`design`](design::design) makes concrete runs — an operating
//! point per pattern ([`operating`]), an excitation around it
//! ([`excitation`]) — predicts the standard errors of θ against run length
//! ([`predict`]), reports it ([`report`]) and checks it by Monte Carlo
//! ([`verify`], on the study engine of `leeway_scenarios::engine`; run by
//! run on a cluster with [`distributed`]); judged by that check, the other
//! runs it tried are verified in turn ([`verified`]).
//!
//! Seeded throughout: the same plan and seed give the same design and the
//! same verification, whatever the thread count.

pub mod bounds;
pub mod compare;
pub mod design;
pub mod distributed;
pub mod document;
pub mod error;
pub mod excitation;
pub mod operating;
pub mod plan;
pub mod predict;
pub mod report;
pub mod signs;
pub mod steady;
pub mod trial;
pub mod verified;
pub mod verify;
