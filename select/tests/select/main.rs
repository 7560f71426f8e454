//! leeway-select end to end: the chosen model's text, recovery of a sparse
//! true structure among candidates on a simulated ship in a coloured current
//! and a measured wind, beside a least-squares selection on the same data.

mod baselines;
mod craft;
mod recovery;
mod tanker;
mod text;
