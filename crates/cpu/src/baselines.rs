//! The seeds' baseline CPU algorithms (thesis two-step, Toy Wars classic, fast hash,
//! connectivity table). Filled in by the SIMD/baselines issue.
