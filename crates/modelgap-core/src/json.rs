//! The loop's results as JSON, the shapes `modelgap compare|explain|fix --json` print:
//! a comparison per output, an explanation with its verdict, reasons, each output's
//! judgement and the ranked candidates. Numbers that are not finite (the score of a fit
//! that failed) are `null`; JSON has no NaN or infinity.

use serde_json::{Map, Value, json};

use crate::compare::Comparison;
use crate::explain::{Explanation, RankedCandidate, Verdict};
use crate::judge::Judgement;

/// A number for JSON: `null` when not finite (JSON has no NaN or infinity).
pub fn finite(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// A comparison as JSON: per output its statistics, noise floor, band and failure windows.
pub fn comparison_json(c: &Comparison) -> Value {
    let outputs: Vec<Value> = c
        .outputs
        .iter()
        .map(|o| {
            let windows: Vec<Value> = o
                .windows
                .iter()
                .map(|w| {
                    json!({
                        "start": finite(w.start),
                        "end": finite(w.end),
                        "peak": finite(w.peak),
                        "peak_time": finite(w.peak_time),
                        "sign": w.sign,
                    })
                })
                .collect();
            json!({
                "name": o.name,
                "unit": o.unit,
                "rms": finite(o.stats.rms),
                "nrms": finite(o.stats.nrms),
                "max_abs": finite(o.stats.max_abs),
                "mean": finite(o.stats.mean),
                "noise_floor": finite(o.noise_floor),
                "noise_given": o.noise_given,
                "noise_method": o.noise_method,
                "rms_over_floor": finite(o.rms_over_floor()),
                "band": finite(o.band),
                "windows": windows,
                "effective_samples": finite(o.effective_samples),
                "quantum": o.quantum.map(finite),
                "not_judged": o.finding,
            })
        })
        .collect();
    json!({
        "model": c.model,
        "samples": c.t.len(),
        "duration": finite(c.t.last().copied().unwrap_or(0.0) - c.t.first().copied().unwrap_or(0.0)),
        "outputs": outputs,
        "warnings": c.warnings,
    })
}

/// One ranked (or chosen) candidate as JSON, its RMS after keyed by output name.
pub fn candidate_json(ex: &Explanation, r: &RankedCandidate) -> Value {
    let params: Vec<Value> = r
        .params
        .iter()
        .map(|p| {
            json!({
                "name": p.name,
                "unit": p.unit,
                "value": finite(p.value),
                "std_error": finite(p.std_error),
                "at_bound": p.at_bound,
            })
        })
        .collect();
    let rms_after: Map<String, Value> = ex
        .outputs
        .iter()
        .zip(&r.rms_after)
        .map(|(o, v)| (o.name.clone(), finite(*v)))
        .collect();
    json!({
        "id": r.candidate.id,
        "name": r.candidate.name,
        "kind": r.candidate.kind.to_string(),
        "acts_on": r.candidate.acts_on,
        "params": params,
        "rms_after": rms_after,
        "score": finite(r.score),
        "qualitative": r.qualitative,
        "qualitative_reason": (!r.qualitative_reason.is_empty()).then_some(&r.qualitative_reason),
        "equivalent": r.equivalent,
        "screened": r.screened,
        "indistinct": r.indistinct,
        "termination": r.termination.to_string(),
        "error": r.error,
        "calibration": r.calibration.as_ref().map(|c| {
            (c.candidate.params.iter().zip(&c.values))
                .map(|(p, v)| json!({"name": p.name, "unit": p.unit, "value": finite(*v)}))
                .collect::<Vec<_>>()
        }),
    })
}

/// The judge's reading of one output's residual as JSON.
pub fn judgement_json(j: &Judgement) -> Value {
    json!({
        "at_floor": j.at_floor,
        "noise_sigma": finite(j.noise_sigma),
        "coloured": j.coloured,
        "correlation_samples": finite(j.correlation_samples),
        "quantum": j.quantum.map(finite),
        "windows": j.windows,
        "bias_z": finite(j.bias_z),
        "input_correlation": j.input.as_ref().map(|c| json!({
            "input": c.input,
            "lag": c.lag,
            "z": finite(c.z),
        })),
        "reasons": j.reasons,
    })
}

/// An explanation as JSON: the verdict, per output the floor and RMS before and after, the
/// ranking, the chosen effects, the margin, the effective sample size and the warnings.
/// Non-finite numbers (a failed fit's score) are `null`.
pub fn explanation_json(ex: &Explanation) -> Value {
    let outputs: Vec<Value> = ex
        .outputs
        .iter()
        .map(|o| {
            let remaining: Vec<Value> = o
                .remaining_windows
                .iter()
                .map(|w| json!({"start": finite(w.start), "end": finite(w.end), "peak": finite(w.peak)}))
                .collect();
            json!({
                "name": o.name,
                "unit": o.unit,
                "noise_floor": finite(o.noise_floor),
                "noise_method": o.noise_method,
                "rms_before": finite(o.rms_before),
                "rms_after": finite(o.rms_after),
                "remaining_windows": remaining,
                "judgement": o.judgement.as_ref().map(judgement_json),
                "noise_rho": o.noise_rho.map(finite),
            })
        })
        .collect();
    let ranked: Vec<Value> = ex.ranked.iter().map(|r| candidate_json(ex, r)).collect();
    let chosen: Vec<Value> = ex
        .chosen
        .iter()
        .map(|c| {
            let mut v = candidate_json(ex, c);
            // The qualitative check runs on the ranking; a chosen effect carries its result.
            if c.qualitative.is_none()
                && let Some(r) = ex.ranked.iter().find(|r| r.candidate.id == c.candidate.id)
            {
                v["qualitative"] = json!(r.qualitative);
                v["qualitative_reason"] =
                    json!((!r.qualitative_reason.is_empty()).then_some(&r.qualitative_reason));
            }
            v
        })
        .collect();
    json!({
        "model": ex.model,
        "verdict": ex.verdict.to_string(),
        "verdict_text": crate::story::verdict_sentence(ex),
        "interrupted": ex.verdict == Verdict::Interrupted,
        "reasons": ex.reasons,
        "outputs": outputs,
        "ranked": ranked,
        "chosen": chosen,
        "margin": finite(ex.margin),
        "effective_samples": finite(ex.effective_samples),
        "warnings": ex.warnings,
        "places": ex.places.iter().map(place_json).collect::<Vec<_>>(),
        "timings": timings_json(&ex.timings),
    })
}

/// Stage timings as JSON: each stage's wall and CPU seconds, and their totals.
pub fn timings_json(laps: &[crate::timing::StageTime]) -> Value {
    let stages: Vec<Value> = (laps.iter())
        .map(
            |l| json!({"stage": l.stage, "wall_s": finite(l.wall_s), "cpu_s": l.cpu_s.map(finite)}),
        )
        .collect();
    let cpu: Option<f64> = laps.iter().map(|l| l.cpu_s).sum();
    json!({
        "stages": stages,
        "wall_s": finite(laps.iter().map(|l| l.wall_s).sum()),
        "cpu_s": cpu.map(finite),
    })
}

/// A place discovery looked at: the missing effort's size and band, and its law.
pub fn place_json(p: &crate::explain::estimate::PlaceFinding) -> Value {
    let law = p.law.as_ref().map(|l| {
        let terms: Vec<Value> = (l.terms.iter())
            .map(|t| {
                json!({
                    "param": t.param,
                    "family": t.family,
                    "term": t.expr_named(),
                    "unit": t.unit,
                    "coefficient": finite(t.coefficient),
                    "std_error": finite(t.std_error),
                    "shape": t.shape.as_ref().map(|s| json!({
                        "name": s.name, "unit": s.unit, "value": finite(s.value),
                    })),
                })
            })
            .collect();
        json!({
            "formula": l.formula(),
            "text": l.describe(),
            "explained": finite(l.explained),
            "residual_rms": finite(l.residual_rms),
            "effective_samples": finite(l.effective_samples),
            "terms": terms,
        })
    });
    json!({
        "location": p.location,
        "place": p.place,
        "quantity": p.quantity,
        "unit": p.unit,
        "explained": finite(p.explained),
        "rms": finite(p.rms),
        "band": finite(p.band),
        "law": law,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_numbers_become_null() {
        assert_eq!(finite(f64::NAN), Value::Null);
        assert_eq!(finite(f64::NEG_INFINITY), Value::Null);
        assert_eq!(finite(1.5), json!(1.5));
    }
}
