//! Predictions already made during one explain, kept so that a point is never
//! simulated twice. A fit evaluates its final point again for the verdict, a
//! finite-difference Jacobian for the uncertainty repeats the last one, a pair
//! search starts where a single ended: on the curtain's drag case 37 of 259
//! simulations (0.13–0.35 s each) were repeats.
//!
//! A prediction depends only on the model and the effects built in, so it is
//! keyed by both (the model by address: only the explain's own models, which
//! live as long as the cache, are kept) and the weighting, which a refined
//! noise floor may change, is applied afresh each time.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use crate::effect::Candidate;
use crate::model::{Model, Prediction};

/// The memory the kept predictions may take, in bytes.
const BUDGET_BYTES: usize = 64 << 20;

/// At most this many predictions are kept, however small.
const MAX_ENTRIES: usize = 256;

/// Predictions of one explain's models, the most recent kept.
pub(super) struct Predictions {
    entries: Mutex<VecDeque<(String, Arc<Prediction>)>>,
    capacity: usize,
}

impl Predictions {
    /// A cache for predictions of `values` numbers each.
    pub(super) fn new(values: usize) -> Self {
        let capacity = (BUDGET_BYTES / (8 * values.max(1))).clamp(2, MAX_ENTRIES);
        Predictions {
            entries: Mutex::new(VecDeque::new()),
            capacity,
        }
    }

    /// The prediction of `model` with `effects`: kept, or made by `predict` and kept.
    pub(super) fn get_or_predict(
        &self,
        model: &dyn Model,
        effects: &[(&Candidate, &[f64])],
        predict: impl FnOnce() -> crate::Result<Prediction>,
    ) -> crate::Result<Arc<Prediction>> {
        let key = key(model, effects);
        if let Ok(entries) = self.entries.lock()
            && let Some((_, p)) = entries.iter().find(|(k, _)| *k == key)
        {
            return Ok(Arc::clone(p));
        }
        let p = Arc::new(predict()?);
        if let Ok(mut entries) = self.entries.lock() {
            if entries.len() >= self.capacity {
                entries.pop_front();
            }
            entries.push_back((key, Arc::clone(&p)));
        }
        Ok(p)
    }
}

/// The model's address, then each effect in full and its values' bits.
fn key(model: &dyn Model, effects: &[(&Candidate, &[f64])]) -> String {
    use std::fmt::Write;
    let mut k = format!("{:p}", model as *const dyn Model as *const u8);
    for (c, values) in effects {
        let _ = write!(k, "|{c:?}=");
        for v in *values {
            let _ = write!(k, "{:x},", v.to_bits());
        }
    }
    k
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;
    use crate::effect::{Effect, EffectKind, EffectParam};
    use crate::recording::Recording;

    /// A model that counts its predictions.
    struct Counting(AtomicUsize);

    impl Model for Counting {
        fn name(&self) -> String {
            "counting".into()
        }
        fn outputs(&self) -> Vec<String> {
            vec!["y".into()]
        }
        fn predict_with(
            &self,
            rec: &Recording,
            effects: &[(&Candidate, &[f64])],
        ) -> crate::Result<Prediction> {
            self.0.fetch_add(1, Ordering::Relaxed);
            let level: f64 = effects.iter().map(|(_, v)| v[0]).sum();
            Ok(Prediction {
                names: vec!["y".into()],
                values: vec![vec![level; rec.len()]],
            })
        }
        fn candidates(&self) -> Vec<Candidate> {
            Vec::new()
        }
        fn with_effects(&self, _: &[Effect]) -> crate::Result<Box<dyn Model>> {
            Ok(Box::new(Counting(AtomicUsize::new(0))))
        }
    }

    fn load() -> Candidate {
        Candidate {
            id: "load".into(),
            name: "a load".into(),
            kind: EffectKind::MissingElement,
            acts_on: "y".into(),
            params: vec![EffectParam::new("F", "N", 0.0, (-10.0, 10.0), 1.0)],
        }
    }

    #[test]
    fn a_point_is_predicted_once_and_another_point_again() {
        let model = Counting(AtomicUsize::new(0));
        let rec = Recording::new(
            vec![0.0, 1.0, 2.0],
            vec![crate::recording::Signal::new("y", vec![0.0; 3])],
        )
        .unwrap();
        let c = load();
        let memo = Predictions::new(3);
        let predict = |v: &[f64]| {
            let effects = [(&c, v)];
            memo.get_or_predict(&model, &effects, || model.predict_with(&rec, &effects))
                .unwrap()
        };
        assert_eq!(predict(&[1.0]).values[0], vec![1.0; 3]);
        assert_eq!(predict(&[1.0]).values[0], vec![1.0; 3]);
        assert_eq!(model.0.load(Ordering::Relaxed), 1);
        // A value one bit away is another point.
        assert_eq!(
            predict(&[1.0 + f64::EPSILON]).values[0][0],
            1.0 + f64::EPSILON
        );
        assert_eq!(model.0.load(Ordering::Relaxed), 2);
    }

    #[test]
    fn the_oldest_prediction_goes_when_the_budget_is_full() {
        let model = Counting(AtomicUsize::new(0));
        let rec = Recording::new(
            vec![0.0],
            vec![crate::recording::Signal::new("y", vec![0.0])],
        )
        .unwrap();
        let c = load();
        // Predictions so large that only two fit in the budget.
        let memo = Predictions::new(BUDGET_BYTES / 8 / 2);
        let predict = |v: f64| {
            let values = [v];
            let effects = [(&c, values.as_slice())];
            memo.get_or_predict(&model, &effects, || model.predict_with(&rec, &effects))
                .unwrap();
        };
        for v in [1.0, 2.0, 3.0, 3.0, 2.0] {
            predict(v);
        }
        assert_eq!(model.0.load(Ordering::Relaxed), 3);
        predict(1.0);
        assert_eq!(model.0.load(Ordering::Relaxed), 4);
    }
}
