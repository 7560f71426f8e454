//! leeway-codegen
