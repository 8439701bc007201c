//! Hard `(A, B, L, O)` triples for the device filters of exact mode
//! ([`FilterFn`]): a filter may leave any triple to the host (`None`), but every sign it
//! certifies must equal [`orient_exact`]'s.
//!
//! ```
//! use shadowvol_test_support::filters;
//!
//! use shadowvol_robust_math::{orient_filter_f32, orient_filter_f64};
//!
//! filters::assert_general_w_left_to_host("robust-math f32", orient_filter_f32);
//! filters::assert_sound("robust-math f32", orient_filter_f32, 1000);
//! // In f64, `w * A` is exact: that filter may certify the general-w triple, correctly.
//! filters::assert_sound("robust-math f64", orient_filter_f64, 1000);
//! ```

use crate::shapes::Rng;
use shadowvol_robust_math::orient_exact;
use shadowvol_silhouette::gpu::twin::FilterFn;

/// One `(A, B, L, O)` input of a filter.
pub type Triple = ([f32; 3], [f32; 3], [f32; 4], [f32; 3]);

/// A point light with `w` = 1.1 placed at `w * A` in `f32`: `fl(w * A)` rounds to exactly
/// `L.xyz`, so the computed `V = L.xyz − w A` is 0 while the exact one is not (the exact sign is
/// not 0). A filter whose error bound is relative to `|V|` certifies a wrong 0 here.
#[must_use]
pub fn general_w() -> Triple {
    let w = 1.1f32;
    let a = [1.3f32, 0.0, 0.0];
    let b = [1.3f32, -1.0, -2.0];
    let o = [1.3f32, 3.0, 1.0];
    (a, b, [w * a[0], 0.0, 0.0, w], o)
}

/// `count` lights with a general `w` in [1, 4) at `w * A` nudged by up to one ulp in one
/// coordinate, for triangles through `A` parallel to the x = `A.x` plane: near-cancellations
/// of `L.xyz − w A`, seeded (the same triples every run).
#[must_use]
pub fn general_w_sweep(count: usize) -> Vec<Triple> {
    let mut rng = Rng::new(77);
    let mut next = move |scale: f32| scale * rng.unit();
    (0..count)
        .map(|_| {
            let w = 1.0 + 3.0 * next(1.0).abs();
            let a: [f32; 3] = std::array::from_fn(|_| next(4.0));
            // B and O share A's x: the triangle lies in the plane x = A.x.
            let [b, o] = [(); 2].map(|()| [a[0], a[1] + next(1.0), a[2] + next(1.0)]);
            let mut l = [w * a[0], w * a[1], w * a[2], w];
            // One coordinate one ulp down, kept, or one ulp up (`next` is uniform in [-1, 1)).
            let (c, nudge) = ((next(1.5) + 1.5) as usize, next(1.0));
            let c = c.min(2);
            if nudge < -1.0 / 3.0 {
                l[c] = l[c].next_down();
            } else if nudge > 1.0 / 3.0 {
                l[c] = l[c].next_up();
            }
            (a, b, l, o)
        })
        .collect()
}

/// Asserts that `filter` (named `what` in the message) leaves [`general_w`] to the host.
///
/// # Panics
/// When the filter certifies a sign there, or the triple's exact sign is 0 (a broken fixture).
pub fn assert_general_w_left_to_host(what: &str, filter: FilterFn) {
    let (a, b, l, o) = general_w();
    let want = orient_exact(a, b, l, o);
    assert_ne!(
        want, 0,
        "w * A is inexact in f32, so the exact sign is not 0"
    );
    let got = filter(a, b, l, o);
    assert_eq!(
        got, None,
        "{what}: certified {got:?} for a general-w light (exact sign {want}); it must go to the host"
    );
}

/// Asserts that every sign `filter` certifies on [`general_w`] and `count` triples of
/// [`general_w_sweep`] equals [`orient_exact`]'s.
///
/// # Panics
/// On the first triple where the filter certifies a wrong sign.
pub fn assert_sound(what: &str, filter: FilterFn, count: usize) {
    for (a, b, l, o) in std::iter::once(general_w()).chain(general_w_sweep(count)) {
        if let Some(got) = filter(a, b, l, o) {
            let want = orient_exact(a, b, l, o);
            assert_eq!(
                got, want,
                "{what}: certified {got} for A={a:?} B={b:?} L={l:?} O={o:?}, exact sign {want}"
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The naive `f32` sign as a "filter" that certifies everything: the sweep must catch it.
    #[test]
    #[should_panic(expected = "certified")]
    fn the_sweep_catches_a_filter_that_certifies_naive_signs() {
        assert_sound(
            "naive",
            |a, b, l, o| Some(shadowvol_robust_math::sign_f32(a, b, l, o)),
            20_000,
        );
    }

    #[test]
    #[should_panic(expected = "must go to the host")]
    fn general_w_catches_a_filter_that_certifies_it() {
        assert_general_w_left_to_host("naive", |a, b, l, o| {
            Some(shadowvol_robust_math::sign_f32(a, b, l, o))
        });
    }
}
