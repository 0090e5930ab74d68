//! `modelgap bond bench`: timings of the bond-graph simulator (being wired).
