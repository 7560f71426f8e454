//! leeway facade (filled in later).
