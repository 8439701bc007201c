//! Differential fuzzing of the exact predicate against the independent big-integer oracle of
//! the robust-math tests: `orient_exact`, `orient_exact_expansion`, and every certified answer of
//! the f64 and f32 filters must equal the oracle's sign, for every finite f32 input.
#![no_main]
use libfuzzer_sys::fuzz_target;
use shadowvol_robust_math::{
    orient_exact, orient_exact_expansion, orient_filter_f32, orient_filter_f64,
};

#[path = "../../crates/robust-math/tests/oracle/mod.rs"]
mod oracle;

fuzz_target!(|raw: [u32; 13]| {
    let f: Vec<f32> = raw.iter().map(|&b| f32::from_bits(b)).collect();
    if f.iter().any(|x| !x.is_finite()) || f[9] < 0.0 {
        return;
    }
    let a = [f[0], f[1], f[2]];
    let b = [f[3], f[4], f[5]];
    let o = [f[6], f[7], f[8]];
    let l = [f[10], f[11], f[12], f[9]];
    let want = oracle::sign_exact(a, b, l, o);
    assert_eq!(orient_exact(a, b, l, o), want, "orient_exact {a:?} {b:?} {l:?} {o:?}");
    assert_eq!(orient_exact_expansion(a, b, l, o), want, "expansion");
    if let Some(s) = orient_filter_f64(a, b, l, o) {
        assert_eq!(s, want, "f64 filter certified a wrong sign");
    }
    if let Some(s) = orient_filter_f32(a, b, l, o) {
        assert_eq!(s, want, "f32 filter certified a wrong sign");
    }
});
