//! leeway-macros
