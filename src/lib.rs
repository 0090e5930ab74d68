//! modelgap facade (being written).
pub use modelgap_bond as bond;
pub use modelgap_core as core_api;
