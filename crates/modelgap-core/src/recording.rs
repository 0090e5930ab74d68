//! [`Recording`]: sampled signals on one strictly increasing time axis, checked at the door.

use serde::{Deserialize, Serialize};

use crate::error::{CoreError, Location, Result};

/// The reserved name of the time column; no signal may use it.
pub const TIME_NAME: &str = "t";

/// The largest magnitude a recording holds, in any column (time included): `1e100`.
///
/// Statistics square values and sum the squares (RMS, noise floors, fits); beyond about
/// `1.3e154` a square overflows to infinity and a comparison would read NaN. `1e100` leaves
/// room for squares (`1e200`) summed over any number of samples, and is far beyond any
/// physical measurement in SI units. A larger value is refused where the recording is made,
/// with [`CoreError::OutOfRange`] naming the sample and the column.
pub const MAX_MAGNITUDE: f64 = 1e100;

/// One named signal: a value per time sample of its [`Recording`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Signal {
    /// The signal's name (non-empty, not `t`, unique within a recording).
    pub name: String,
    /// One value per time sample, in SI units.
    pub values: Vec<f64>,
}

impl Signal {
    /// Creates a signal from a name and its values.
    pub fn new(name: impl Into<String>, values: Vec<f64>) -> Self {
        Self {
            name: name.into(),
            values,
        }
    }
}

/// Sampled signals sharing one time axis.
///
/// Invariants, checked by [`Recording::new`] and kept by every method: at least one sample;
/// time finite and strictly increasing (s); every value, time included, finite and at most
/// [`MAX_MAGNITUDE`] in magnitude; one value per time sample for every signal, with a
/// unique, non-empty name other than `t`. Past this type, code may assume finite data whose
/// squares and sums of squares are finite.
///
/// Deserializing (serde) checks the same invariants.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RecordingParts")]
pub struct Recording {
    t: Vec<f64>,
    signals: Vec<Signal>,
}

/// The unchecked shape of a [`Recording`], for deserializing.
#[derive(Deserialize)]
struct RecordingParts {
    t: Vec<f64>,
    signals: Vec<Signal>,
}

impl TryFrom<RecordingParts> for Recording {
    type Error = CoreError;

    fn try_from(parts: RecordingParts) -> Result<Self> {
        Self::new(parts.t, parts.signals)
    }
}

impl Recording {
    /// Creates a recording from a time axis (s) and signals, checking every invariant.
    ///
    /// # Errors
    ///
    /// [`CoreError::EmptyRecording`] when `t` is empty; [`CoreError::NonFinite`],
    /// [`CoreError::OutOfRange`] (beyond [`MAX_MAGNITUDE`]) or
    /// [`CoreError::NonIncreasingTime`] (with the sample index) for a bad time or value;
    /// [`CoreError::LengthMismatch`], [`CoreError::InvalidSignalName`] or
    /// [`CoreError::DuplicateSignal`] for a bad signal.
    ///
    /// # Example
    ///
    /// ```
    /// # use modelgap_core::{Recording, Signal};
    /// let rec = Recording::new(vec![0.0, 0.1, 0.2], vec![Signal::new("i", vec![1.0, 2.0, 3.0])])?;
    /// assert_eq!(rec.len(), 3);
    /// assert_eq!(rec.values("i")?, &[1.0, 2.0, 3.0]);
    /// # Ok::<(), modelgap_core::CoreError>(())
    /// ```
    pub fn new(t: Vec<f64>, signals: Vec<Signal>) -> Result<Self> {
        check_time(&t)?;
        let mut rec = Self {
            t,
            signals: Vec::with_capacity(signals.len()),
        };
        for signal in signals {
            rec.push_signal(signal)?;
        }
        Ok(rec)
    }

    /// The time axis (s), strictly increasing.
    pub fn t(&self) -> &[f64] {
        &self.t
    }

    /// All signals, in order.
    pub fn signals(&self) -> &[Signal] {
        &self.signals
    }

    /// The signal called `name`, if any.
    pub fn signal(&self, name: &str) -> Option<&Signal> {
        self.signals.iter().find(|s| s.name == name)
    }

    /// The values of the signal called `name`.
    ///
    /// # Errors
    ///
    /// [`CoreError::UnknownSignal`], listing the available names, when there is no such signal.
    pub fn values(&self, name: &str) -> Result<&[f64]> {
        self.signal(name)
            .map(|s| s.values.as_slice())
            .ok_or_else(|| self.unknown(name))
    }

    /// The signal names, in order.
    pub fn names(&self) -> Vec<&str> {
        self.signals.iter().map(|s| s.name.as_str()).collect()
    }

    /// The number of time samples (at least 1).
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Always `false`: a recording has at least one sample. Present by convention with `len`.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// The time from the first to the last sample (s); 0 for a single sample.
    pub fn duration(&self) -> f64 {
        match (self.t.first(), self.t.last()) {
            (Some(first), Some(last)) => last - first,
            _ => 0.0,
        }
    }

    /// Adds a signal after the existing ones.
    ///
    /// # Errors
    ///
    /// [`CoreError::LengthMismatch`] when it has not one value per time sample,
    /// [`CoreError::NonFinite`] for a NaN or infinite value, [`CoreError::OutOfRange`] for a
    /// value beyond [`MAX_MAGNITUDE`], [`CoreError::InvalidSignalName`]
    /// for an empty name or `t`, [`CoreError::DuplicateSignal`] when the name is taken. The
    /// recording is unchanged on error.
    pub fn push_signal(&mut self, signal: Signal) -> Result<()> {
        check_name(&signal.name)?;
        if self.signal(&signal.name).is_some() {
            return Err(CoreError::DuplicateSignal {
                name: signal.name,
                at: None,
                path: None,
            });
        }
        if signal.values.len() != self.t.len() {
            return Err(CoreError::LengthMismatch {
                name: signal.name,
                expected: self.t.len(),
                found: signal.values.len(),
            });
        }
        if let Some((i, &value)) = signal
            .values
            .iter()
            .enumerate()
            .find(|(_, v)| !v.is_finite())
        {
            return Err(CoreError::NonFinite {
                at: Location::Sample(i),
                column: signal.name,
                value,
                path: None,
            });
        }
        if let Some((i, &value)) = signal
            .values
            .iter()
            .enumerate()
            .find(|(_, v)| v.abs() > MAX_MAGNITUDE)
        {
            return Err(CoreError::OutOfRange {
                at: Location::Sample(i),
                t: self.t[i],
                column: signal.name,
                value,
                limit: MAX_MAGNITUDE,
                path: None,
            });
        }
        self.signals.push(signal);
        Ok(())
    }

    /// A recording with only the named signals, in the order given, on the same time axis.
    ///
    /// # Errors
    ///
    /// [`CoreError::UnknownSignal`] for a name the recording lacks,
    /// [`CoreError::DuplicateSignal`] for a name given twice.
    pub fn select(&self, names: &[&str]) -> Result<Recording> {
        let mut signals: Vec<Signal> = Vec::with_capacity(names.len());
        for &name in names {
            if signals.iter().any(|s| s.name == name) {
                return Err(CoreError::DuplicateSignal {
                    name: name.to_owned(),
                    at: None,
                    path: None,
                });
            }
            let signal = self.signal(name).ok_or_else(|| self.unknown(name))?;
            signals.push(signal.clone());
        }
        Ok(Self {
            t: self.t.clone(),
            signals,
        })
    }

    /// The samples with `t0 <= t <= t1` (s), all signals kept.
    ///
    /// # Errors
    ///
    /// [`CoreError::InvalidArgument`] when a bound is NaN or `t0 > t1`;
    /// [`CoreError::EmptyRecording`] when no sample lies in the interval.
    pub fn slice_time(&self, t0: f64, t1: f64) -> Result<Recording> {
        if t0.is_nan() || t1.is_nan() || t0 > t1 {
            return Err(CoreError::InvalidArgument {
                name: "t0, t1",
                reason: format!("expected an interval t0 <= t1, found [{t0}, {t1}] s"),
            });
        }
        let start = self.t.partition_point(|&t| t < t0);
        let end = self.t.partition_point(|&t| t <= t1);
        if start >= end {
            return Err(CoreError::EmptyRecording { path: None });
        }
        Ok(Self {
            t: self.t[start..end].to_vec(),
            signals: self
                .signals
                .iter()
                .map(|s| Signal::new(s.name.clone(), s.values[start..end].to_vec()))
                .collect(),
        })
    }

    /// The value of signal `name` at time `t` (s), linearly interpolated between samples and
    /// held at the first or last value outside the recorded interval.
    ///
    /// # Errors
    ///
    /// [`CoreError::UnknownSignal`] for a name the recording lacks;
    /// [`CoreError::InvalidArgument`] when `t` is NaN.
    pub fn sample_at(&self, name: &str, t: f64) -> Result<f64> {
        let values = self.values(name)?;
        if t.is_nan() {
            return Err(CoreError::InvalidArgument {
                name: "t",
                reason: "expected a time, found NaN".to_owned(),
            });
        }
        // `hi` is the first sample strictly after `t`.
        let hi = self.t.partition_point(|&ti| ti <= t);
        if hi == 0 {
            return Ok(values[0]);
        }
        if hi == self.t.len() {
            return Ok(values[hi - 1]);
        }
        let lo = hi - 1;
        let (t_lo, t_hi) = (self.t[lo], self.t[hi]);
        let w = (t - t_lo) / (t_hi - t_lo);
        Ok(values[lo] + w * (values[hi] - values[lo]))
    }

    fn unknown(&self, name: &str) -> CoreError {
        CoreError::UnknownSignal {
            name: name.to_owned(),
            available: self.signals.iter().map(|s| s.name.clone()).collect(),
        }
    }
}

/// Checks that a time axis is non-empty, finite and strictly increasing.
fn check_time(t: &[f64]) -> Result<()> {
    if t.is_empty() {
        return Err(CoreError::EmptyRecording { path: None });
    }
    for (i, &ti) in t.iter().enumerate() {
        if !ti.is_finite() {
            return Err(CoreError::NonFinite {
                at: Location::Sample(i),
                column: TIME_NAME.to_owned(),
                value: ti,
                path: None,
            });
        }
        if ti.abs() > MAX_MAGNITUDE {
            return Err(CoreError::OutOfRange {
                at: Location::Sample(i),
                t: ti,
                column: TIME_NAME.to_owned(),
                value: ti,
                limit: MAX_MAGNITUDE,
                path: None,
            });
        }
        if i > 0 && ti <= t[i - 1] {
            return Err(CoreError::NonIncreasingTime {
                at: Location::Sample(i),
                t_prev: t[i - 1],
                t: ti,
                path: None,
            });
        }
    }
    Ok(())
}

/// Checks that a signal name is non-empty and not the time column's.
pub(crate) fn check_name(name: &str) -> Result<()> {
    let reason = if name.is_empty() {
        "a signal name must not be empty"
    } else if name == TIME_NAME {
        "`t` is reserved for time"
    } else {
        return Ok(());
    };
    Err(CoreError::InvalidSignalName {
        name: name.to_owned(),
        reason,
        at: None,
        path: None,
    })
}

#[cfg(test)]
mod tests {
    use approx::assert_relative_eq;

    use super::*;

    fn motor() -> Recording {
        Recording::new(
            vec![0.0, 1.0, 2.0, 4.0],
            vec![
                Signal::new("i", vec![0.0, 10.0, 20.0, 40.0]),
                Signal::new("omega", vec![1.0, 1.0, 3.0, 3.0]),
            ],
        )
        .unwrap()
    }

    #[test]
    fn new_rejects_empty_time() {
        let e = Recording::new(vec![], vec![]).unwrap_err();
        assert!(matches!(e, CoreError::EmptyRecording { .. }));
    }

    #[test]
    fn new_rejects_repeated_time_with_sample_index() {
        let e = Recording::new(vec![0.0, 0.5, 0.5], vec![]).unwrap_err();
        assert!(matches!(
            e,
            CoreError::NonIncreasingTime { at: Location::Sample(2), t_prev, t, .. }
                if t_prev == 0.5 && t == 0.5
        ));
    }

    #[test]
    fn new_rejects_nan_time() {
        let e = Recording::new(vec![0.0, f64::NAN], vec![]).unwrap_err();
        assert!(matches!(
            e,
            CoreError::NonFinite { at: Location::Sample(1), ref column, .. } if column == "t"
        ));
    }

    #[test]
    fn new_rejects_infinite_value_naming_the_signal() {
        let e = Recording::new(
            vec![0.0, 1.0],
            vec![Signal::new("i", vec![1.0, f64::INFINITY])],
        )
        .unwrap_err();
        assert!(matches!(
            e,
            CoreError::NonFinite { at: Location::Sample(1), ref column, .. } if column == "i"
        ));
    }

    /// Issue 11: a value near `f64::MAX` made compare print `NaN× the noise floor`.
    #[test]
    fn new_rejects_huge_finite_values_naming_sample_and_column() {
        let e = Recording::new(
            vec![0.0, 0.5, 1.0],
            vec![Signal::new("omega", vec![1.0, 2.0, -1.7e308])],
        )
        .unwrap_err();
        assert!(matches!(
            e,
            CoreError::OutOfRange { at: Location::Sample(2), ref column, value, t, .. }
                if column == "omega" && value == -1.7e308 && t == 1.0
        ));
        let text = e.to_string();
        assert!(
            text.contains("sample 2") && text.contains("`omega`") && text.contains("1e100"),
            "{text}"
        );
        let e = Recording::new(vec![0.0, 2e100], vec![]).unwrap_err();
        assert!(matches!(e, CoreError::OutOfRange { ref column, .. } if column == "t"));
        // The limit itself is accepted: its square and sums of squares stay finite.
        let rec = Recording::new(
            vec![0.0, 1.0],
            vec![Signal::new("x", vec![MAX_MAGNITUDE, -MAX_MAGNITUDE])],
        )
        .unwrap();
        let sum_sq: f64 = rec.values("x").unwrap().iter().map(|v| v * v).sum();
        assert!(sum_sq.is_finite());
    }

    #[test]
    fn new_rejects_signal_of_wrong_length() {
        let e = Recording::new(vec![0.0, 1.0], vec![Signal::new("i", vec![1.0])]).unwrap_err();
        assert!(matches!(
            e,
            CoreError::LengthMismatch {
                expected: 2,
                found: 1,
                ..
            }
        ));
    }

    #[test]
    fn new_rejects_reserved_empty_and_duplicate_names() {
        for name in ["t", ""] {
            let e = Recording::new(vec![0.0], vec![Signal::new(name, vec![1.0])]).unwrap_err();
            assert!(matches!(e, CoreError::InvalidSignalName { .. }), "{name:?}");
        }
        let e = Recording::new(
            vec![0.0],
            vec![Signal::new("i", vec![1.0]), Signal::new("i", vec![2.0])],
        )
        .unwrap_err();
        assert!(matches!(e, CoreError::DuplicateSignal { ref name, .. } if name == "i"));
    }

    #[test]
    fn values_of_unknown_signal_lists_available_names() {
        let e = motor().values("torque").unwrap_err();
        assert!(matches!(
            e,
            CoreError::UnknownSignal { ref available, .. } if available == &["i", "omega"]
        ));
    }

    #[test]
    fn accessors_report_shape() {
        let rec = motor();
        assert_eq!(rec.len(), 4);
        assert!(!rec.is_empty());
        assert_eq!(rec.names(), vec!["i", "omega"]);
        assert_eq!(rec.duration(), 4.0);
        assert_eq!(rec.signal("omega").map(|s| s.values[2]), Some(3.0));
        assert!(rec.signal("x").is_none());
    }

    #[test]
    fn push_signal_validates_and_leaves_recording_unchanged_on_error() {
        let mut rec = motor();
        assert!(rec.push_signal(Signal::new("i", vec![0.0; 4])).is_err());
        assert!(rec.push_signal(Signal::new("u", vec![0.0; 3])).is_err());
        assert_eq!(rec, motor());
        rec.push_signal(Signal::new("u", vec![24.0; 4])).unwrap();
        assert_eq!(rec.names(), vec!["i", "omega", "u"]);
    }

    #[test]
    fn select_keeps_requested_order_and_rejects_unknown_or_repeated() {
        let rec = motor();
        let sel = rec.select(&["omega", "i"]).unwrap();
        assert_eq!(sel.names(), vec!["omega", "i"]);
        assert_eq!(sel.t(), rec.t());
        assert!(matches!(
            rec.select(&["x"]),
            Err(CoreError::UnknownSignal { .. })
        ));
        assert!(matches!(
            rec.select(&["i", "i"]),
            Err(CoreError::DuplicateSignal { .. })
        ));
    }

    #[test]
    fn slice_time_is_inclusive_and_rejects_empty_or_reversed_intervals() {
        let rec = motor();
        let s = rec.slice_time(1.0, 2.0).unwrap();
        assert_eq!(s.t(), &[1.0, 2.0]);
        assert_eq!(s.values("i").unwrap(), &[10.0, 20.0]);
        assert!(matches!(
            rec.slice_time(2.5, 3.5),
            Err(CoreError::EmptyRecording { .. })
        ));
        assert!(matches!(
            rec.slice_time(2.0, 1.0),
            Err(CoreError::InvalidArgument { .. })
        ));
    }

    #[test]
    fn sample_at_interpolates_and_clamps() {
        let rec = motor();
        // 0.25 of the way from (2, 20) to (4, 40): exact in binary, so a tight epsilon.
        assert_relative_eq!(rec.sample_at("i", 2.5).unwrap(), 25.0, epsilon = 1e-12);
        assert_eq!(rec.sample_at("i", 1.0).unwrap(), 10.0);
        assert_eq!(rec.sample_at("i", -3.0).unwrap(), 0.0);
        assert_eq!(rec.sample_at("i", 9.0).unwrap(), 40.0);
        assert!(rec.sample_at("i", f64::NAN).is_err());
        assert!(rec.sample_at("x", 1.0).is_err());
    }

    #[test]
    fn serde_round_trip_and_deserialize_validates() {
        let rec = motor();
        let json = serde_json::to_string(&rec).unwrap();
        let back: Recording = serde_json::from_str(&json).unwrap();
        assert_eq!(back, rec);
        let bad = r#"{"t":[0.0,0.0],"signals":[]}"#;
        assert!(serde_json::from_str::<Recording>(bad).is_err());
    }
}
