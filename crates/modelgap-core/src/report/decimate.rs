//! Min/max decimation: a long series reduced to what a plot of a given width can show.

/// A series ready to draw: polylines broken where values are not finite.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Decimated {
    /// Runs of `(t, value)` points with finite values, in time order.
    pub segments: Vec<Vec<(f64, f64)>>,
    /// How many samples were not finite (not drawn).
    pub n_non_finite: usize,
}

impl Decimated {
    /// The smallest and largest value drawn, `None` when nothing is drawn.
    pub fn value_range(&self) -> Option<(f64, f64)> {
        self.segments
            .iter()
            .flatten()
            .fold(None, |acc, &(_, v)| match acc {
                None => Some((v, v)),
                Some((lo, hi)) => Some((v.min(lo), v.max(hi))),
            })
    }

    /// The number of points drawn.
    #[cfg(test)]
    pub fn n_points(&self) -> usize {
        self.segments.iter().map(Vec::len).sum()
    }
}

/// Reduces `(t, values)` to at most two points per column when `t[0]..t[last]` is split into
/// `columns` equal columns: the minimum and the maximum of each column's samples, in time
/// order. Drawn as a polyline, this covers the same pixels as the full series (the visual
/// envelope), with at most `2 · columns` points per run of finite values.
///
/// Series of at most `2 · columns` samples are kept whole. Non-finite values break the line.
/// `t` must be non-decreasing and as long as `values` (checked by the caller).
pub(crate) fn min_max(t: &[f64], values: &[f64], columns: usize) -> Decimated {
    debug_assert_eq!(t.len(), values.len());
    let columns = columns.max(1);
    let n_non_finite = values.iter().filter(|v| !v.is_finite()).count();
    let mut out = Decimated {
        segments: Vec::new(),
        n_non_finite,
    };
    let (Some(&t0), Some(&t1)) = (t.first(), t.last()) else {
        return out;
    };
    let keep_all = t.len() <= 2 * columns;
    let span = t1 - t0;
    let column_of = |ti: f64| -> usize {
        if span > 0.0 {
            // In [0, columns): the last sample falls into the last column.
            (((ti - t0) / span * columns as f64).floor() as usize).min(columns - 1)
        } else {
            0
        }
    };

    let mut current: Vec<(f64, f64)> = Vec::new();
    // The open column: (column, index of its minimum, index of its maximum).
    let mut bucket: Option<(usize, usize, usize)> = None;
    let flush = |bucket: &mut Option<(usize, usize, usize)>, current: &mut Vec<(f64, f64)>| {
        if let Some((_, lo, hi)) = bucket.take() {
            let (first, second) = if lo <= hi { (lo, hi) } else { (hi, lo) };
            current.push((t[first], values[first]));
            if second != first {
                current.push((t[second], values[second]));
            }
        }
    };
    for (i, (&ti, &v)) in t.iter().zip(values).enumerate() {
        if !v.is_finite() {
            flush(&mut bucket, &mut current);
            if !current.is_empty() {
                out.segments.push(std::mem::take(&mut current));
            }
            continue;
        }
        if keep_all {
            current.push((ti, v));
            continue;
        }
        let column = column_of(ti);
        match &mut bucket {
            Some((c, lo, hi)) if *c == column => {
                if v < values[*lo] {
                    *lo = i;
                }
                if v > values[*hi] {
                    *hi = i;
                }
            }
            _ => {
                flush(&mut bucket, &mut current);
                bucket = Some((column, i, i));
            }
        }
    }
    flush(&mut bucket, &mut current);
    if !current.is_empty() {
        out.segments.push(current);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_series_are_kept_whole() {
        let t = [0.0, 1.0, 2.0];
        let d = min_max(&t, &[1.0, 2.0, 3.0], 10);
        assert_eq!(d.segments, vec![vec![(0.0, 1.0), (1.0, 2.0), (2.0, 3.0)]]);
    }

    #[test]
    fn long_series_keep_their_envelope_in_few_points() {
        let n = 200_000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-4).collect();
        // Noise-like: alternating ±1 on a slow ramp, with one spike.
        let mut v: Vec<f64> = (0..n)
            .map(|k| k as f64 * 1e-5 + if k % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        v[123_457] = 50.0;
        let d = min_max(&t, &v, 800);
        assert!(d.n_points() <= 1600, "{} points", d.n_points());
        let (lo, hi) = d.value_range().unwrap();
        let true_lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        assert_eq!((lo, hi), (true_lo, 50.0));
        // Points stay in time order.
        assert!(d.segments[0].windows(2).all(|w| w[0].0 <= w[1].0));
    }

    #[test]
    fn non_finite_values_break_the_line() {
        let t = [0.0, 1.0, 2.0, 3.0, 4.0];
        let d = min_max(&t, &[1.0, f64::NAN, 2.0, f64::INFINITY, 3.0], 10);
        assert_eq!(d.segments.len(), 3);
        assert_eq!(d.n_non_finite, 2);
    }

    #[test]
    fn empty_and_constant_time_series_do_not_panic() {
        assert_eq!(min_max(&[], &[], 10).n_points(), 0);
        let t = vec![1.0; 100];
        let v: Vec<f64> = (0..100).map(f64::from).collect();
        let d = min_max(&t, &v, 10);
        assert_eq!(d.segments, vec![vec![(1.0, 0.0), (1.0, 99.0)]]);
    }
}
