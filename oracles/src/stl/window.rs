//! Sliding-window minimum and maximum (Lemire 2006): a deque of indices whose values are
//! monotone, so each element enters and leaves it once.

use std::collections::VecDeque;

/// `out[i] = min(values[j] for j in i+a ..= i+b, j < n)`, `+inf` when that window is empty.
/// O(n) whatever the window. `values` has length `n`; `a <= b`.
pub fn sliding_min(values: &[f64], a: usize, b: usize) -> Vec<f64> {
    sliding(values, a, b, |x, y| x <= y, f64::INFINITY)
}

/// As [`sliding_min`] with the maximum (`-inf` for an empty window).
pub fn sliding_max(values: &[f64], a: usize, b: usize) -> Vec<f64> {
    sliding(values, a, b, |x, y| x >= y, f64::NEG_INFINITY)
}

/// `keep(x, y)`: whether `x` dominates `y` (for the minimum, `x <= y`). NaN never dominates, so
/// a NaN sample stays in the window until it leaves it.
fn sliding(
    values: &[f64],
    a: usize,
    b: usize,
    dominates: impl Fn(f64, f64) -> bool,
    empty: f64,
) -> Vec<f64> {
    let n = values.len();
    let mut out = vec![empty; n];
    let mut deque: VecDeque<usize> = VecDeque::new();
    // `next` is the first index not yet pushed.
    let mut next = a.min(n);
    for (i, slot) in out.iter_mut().enumerate() {
        let (lo, hi) = (
            i.saturating_add(a),
            i.saturating_add(b).min(n.saturating_sub(1)),
        );
        if lo >= n {
            break; // every later window is empty too
        }
        while next <= hi {
            while deque
                .back()
                .is_some_and(|&k| dominates(values[next], values[k]))
            {
                deque.pop_back();
            }
            deque.push_back(next);
            next += 1;
        }
        while deque.front().is_some_and(|&k| k < lo) {
            deque.pop_front();
        }
        if let Some(&k) = deque.front() {
            *slot = values[k];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn naive(values: &[f64], a: usize, b: usize, min: bool) -> Vec<f64> {
        (0..values.len())
            .map(|i| {
                let w = values.iter().skip(i + a).take(b - a + 1);
                if min {
                    w.copied().fold(f64::INFINITY, f64::min)
                } else {
                    w.copied().fold(f64::NEG_INFINITY, f64::max)
                }
            })
            .collect()
    }

    #[test]
    fn small_cases() {
        let v = [3.0, 1.0, 4.0, 1.0, 5.0, 9.0, 2.0];
        assert_eq!(sliding_min(&v, 0, 2), [1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0]);
        assert_eq!(
            sliding_max(&v, 1, 2),
            [4.0, 4.0, 5.0, 9.0, 9.0, 2.0, f64::NEG_INFINITY]
        );
        assert_eq!(sliding_min(&[], 0, 3), Vec::<f64>::new());
    }

    proptest! {
        #[test]
        fn equals_the_naive_window(values in prop::collection::vec(-100.0f64..100.0, 0..60),
                                   a in 0usize..8, w in 0usize..8) {
            let b = a + w;
            prop_assert_eq!(sliding_min(&values, a, b), naive(&values, a, b, true));
            prop_assert_eq!(sliding_max(&values, a, b), naive(&values, a, b, false));
        }
    }
}
