//! The loop's story for people: where the model fails, what is missing,
//! the error before and after — as terminal text and as the HTML report.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::compare::Comparison;
use crate::effect::Effect;
use crate::error::Result;
use crate::explain::{Explanation, FittedParam, Verdict};
use crate::recording::Recording;
use crate::report::{
    ComparisonChannels, RankingBar, Report, SeriesPlot, format_number, write_comparison_mcap,
    write_html,
};

pub(crate) fn num(v: f64) -> String {
    format_number(v)
}

/// A unit as written after a number: `" N m"`, or nothing for a dimensionless
/// quantity (unit `"1"` or none), so no number reads "0.8 1".
pub fn unit_suffix(unit: &str) -> String {
    match unit.trim() {
        "" | "1" => String::new(),
        u => format!(" {u}"),
    }
}

/// The widest line the loop's text output holds (characters); longer lines are wrapped by
/// [`wrap_text`]. Under 100 with room for the demo's indent of 3.
pub const TEXT_WIDTH: usize = 96;

/// Wraps every line of `text` longer than `width` characters at spaces, continuing it
/// indented 4 spaces deeper than the line began; shorter lines (and the alignment spaces in
/// them) are kept as they are. A single word longer than `width` stays whole.
///
/// # Example
/// ```
/// # use modelgap_core::story::wrap_text;
/// let text = "  fails at 0.1–0.5 s, 0.7–0.9 s, 1.2–1.4 s\nshort\n";
/// assert_eq!(wrap_text(text, 28), "  fails at 0.1–0.5 s,\n      0.7–0.9 s, 1.2–1.4 s\nshort\n");
/// ```
pub fn wrap_text(text: &str, width: usize) -> String {
    let mut out = String::with_capacity(text.len() + text.len() / 16);
    for line in text.split_inclusive('\n') {
        let (body, newline) = match line.strip_suffix('\n') {
            Some(b) => (b, "\n"),
            None => (line, ""),
        };
        if body.chars().count() <= width {
            out.push_str(line);
            continue;
        }
        let lead = body.len() - body.trim_start_matches(' ').len();
        let hang = " ".repeat((lead + 4).min(width / 2));
        let mut words = body[lead..].split(' ');
        // The first word always starts the line; the text after the indent is not empty.
        let mut current = body[..lead].to_owned();
        current.push_str(words.next().unwrap_or(""));
        let mut current_len = current.chars().count();
        for word in words {
            let len = word.chars().count();
            // Empty words are runs of spaces (alignment): kept, never a place to break; nor
            // before a percent sign, which belongs to its number.
            if word.is_empty() || word.starts_with('%') || current_len + 1 + len <= width {
                current.push(' ');
                current.push_str(word);
                current_len += 1 + len;
            } else {
                out.push_str(current.trim_end());
                out.push('\n');
                current.clone_from(&hang);
                current.push_str(word);
                current_len = hang.len() + len;
            }
        }
        out.push_str(current.trim_end());
        out.push_str(newline);
    }
    out
}

/// A fitted parameter as `name = value ± std_error unit`; a value the fit
/// ended on a bound of reads `name = value unit (at its upper bound)`, with no
/// `±` (it is a limit, not an estimate), and one the data do not determine has
/// no `±` either.
pub fn param_text(p: &FittedParam) -> String {
    let unit = unit_suffix(&p.unit);
    match &p.at_bound {
        Some(bound) => format!("{} = {}{unit} (at its {bound} bound)", p.name, num(p.value)),
        None if p.std_error.is_finite() => {
            format!("{} = {} ± {}{unit}", p.name, num(p.value), num(p.std_error))
        }
        None => format!("{} = {}{unit}", p.name, num(p.value)),
    }
}

/// The verdict as one sentence.
pub fn verdict_sentence(ex: &Explanation) -> String {
    let names = |i: usize| {
        ex.chosen
            .get(i)
            .map_or(String::new(), |c| c.candidate.name.clone())
    };
    match ex.verdict {
        Verdict::NothingMissing => {
            "Nothing is missing: the model already leaves only what noise leaves.".to_string()
        }
        Verdict::EffectFound => format!("Missing: {}.", names(0)),
        Verdict::TwoEffects => format!("Missing: {}, and {}.", names(0), names(1)),
        Verdict::Partial => {
            let (which, verb) = match ex.chosen.len() {
                0 => ("no candidate".to_string(), "removes"),
                1 => (names(0), "removes"),
                _ => (format!("{}, with {},", names(0), names(1)), "remove"),
            };
            format!(
                "Partly explained: {which} {verb} part of the error, but what remains is not noise — the true effect is probably not on the menu."
            )
        }
        Verdict::Unexplained => {
            "Not explained: the model fails, and no candidate effect on the menu \
             explains any of it significantly."
                .to_string()
        }
        Verdict::CannotJudge => {
            let why = ex
                .reasons
                .first()
                .map_or("the recording cannot be judged", String::as_str);
            let stop = if why.ends_with(['?', '.']) { "" } else { "." };
            format!("Cannot judge: {why}{stop}")
        }
        Verdict::Interrupted => {
            "Interrupted before a verdict: no effect was chosen and nothing was written."
                .to_string()
        }
    }
}

/// A share in [0, 1] as a percentage: `62 %`, `0.4 %`, `0 %`.
pub(crate) fn percent(share: f64) -> String {
    let p = 100.0 * share;
    if p == 0.0 || p >= 10.0 {
        format!("{p:.0} %")
    } else {
        format!("{p:.1} %")
    }
}

/// The error before → after per output, as text.
pub fn before_after_text(before: &Comparison, after: &Comparison) -> String {
    let share = |w: &[crate::residual::FailureWindow], t: &[f64]| {
        crate::residual::share_outside(w.iter().map(|w| (w.start, w.end)), t)
    };
    let mut s = String::new();
    for o in &before.outputs {
        let Some(a) = after.output(&o.name) else {
            continue;
        };
        let change = if o.stats.rms > 0.0 {
            let ratio = a.stats.rms / o.stats.rms;
            if ratio <= 1.0 {
                format!("{:.0} % lower", 100.0 * (1.0 - ratio))
            } else {
                format!("{:.0} % higher", 100.0 * (ratio - 1.0))
            }
        } else {
            String::from("was already 0")
        };
        s.push_str(&format!(
            "  {:<8} RMS {} → {} {} ({change}; {:.1}× → {:.1}× the noise floor {}), outside \
             its band {} → {} of the record\n",
            o.name,
            num(o.stats.rms),
            num(a.stats.rms),
            o.unit,
            o.rms_over_floor(),
            a.rms_over_floor(),
            num(o.noise_floor),
            percent(share(&o.windows, &before.t)),
            percent(share(&a.windows, &after.t)),
        ));
    }
    wrap_text(&s, TEXT_WIDTH)
}

/// Where the model fails, output by output, as text.
pub fn comparison_text(c: &Comparison) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "model {} against the recording ({} samples, {} s):",
        c.model,
        c.t.len(),
        num(c.t.last().copied().unwrap_or(0.0) - c.t.first().copied().unwrap_or(0.0))
    );
    for o in &c.outputs {
        if let Some(f) = &o.finding {
            let _ = writeln!(
                s,
                "  {:<8} RMS {} {}, max {}: not judged ({f})",
                o.name,
                num(o.stats.rms),
                o.unit,
                num(o.stats.max_abs),
            );
            continue;
        }
        let _ = writeln!(
            s,
            "  {:<8} RMS {} {} ({:.1}× the noise floor {}), max {}, normalised RMS {:.2} %",
            o.name,
            num(o.stats.rms),
            o.unit,
            o.rms_over_floor(),
            num(o.noise_floor),
            num(o.stats.max_abs),
            100.0 * o.stats.nrms
        );
        if let Some(q) = o.quantum {
            let _ = writeln!(
                s,
                "           quantised in steps of {} {}: the floor includes their rounding error",
                num(q),
                o.unit
            );
        }
        if o.windows.is_empty() {
            let _ = writeln!(
                s,
                "           never leaves its band of ±{} {}",
                num(o.band),
                o.unit
            );
        } else {
            let shown: Vec<String> = crate::residual::largest_windows(&o.windows, 6)
                .into_iter()
                .map(|w| {
                    format!(
                        "{}–{} s (peak {} at {} s)",
                        num(w.start),
                        num(w.end),
                        num(w.peak),
                        num(w.peak_time)
                    )
                })
                .collect();
            let more = if o.windows.len() > 6 {
                format!(" and {} with smaller peaks", o.windows.len() - 6)
            } else {
                String::new()
            };
            let _ = writeln!(
                s,
                "           fails (outside ±{} {}) at {}{more}",
                num(o.band),
                o.unit,
                shown.join(", ")
            );
        }
    }
    for w in c
        .warnings
        .iter()
        .filter(|w| !c.outputs.iter().any(|o| o.finding.as_ref() == Some(*w)))
    {
        let _ = writeln!(s, "warning: {w}");
    }
    wrap_text(&s, TEXT_WIDTH)
}

/// What the scores are taken over, in words: a BIC difference on the residual whitened with
/// each output's AR(1) noise coefficient, and what a coefficient at its cap means.
pub fn scoring_basis(ex: &Explanation) -> String {
    let rhos: Vec<(&str, f64)> = (ex.outputs.iter())
        .filter_map(|o| Some((o.name.as_str(), o.noise_rho?)))
        .collect();
    if rhos.is_empty() {
        return format!(
            "a BIC difference with {} effective samples",
            num(ex.effective_samples)
        );
    }
    let list = if rhos.len() <= 3 {
        (rhos.iter())
            .map(|(n, r)| format!("{n} {r:.3}"))
            .collect::<Vec<_>>()
            .join(", ")
    } else {
        let lo = rhos.iter().map(|r| r.1).fold(f64::INFINITY, f64::min);
        let hi = rhos.iter().map(|r| r.1).fold(f64::NEG_INFINITY, f64::max);
        format!("{lo:.3}–{hi:.3} over {} outputs", rhos.len())
    };
    // Within a hundredth of 1 the whitened residual is, in effect, its changes from sample
    // to sample.
    let capped = rhos.iter().any(|r| r.1 >= 0.99);
    format!(
        "a BIC difference on the residual whitened with the noise's AR(1) coefficient ({list}){}",
        if capped {
            "; at or near its cap of 0.999 the residual is mostly model error, and the scores \
             weigh its changes from sample to sample"
        } else {
            ""
        }
    )
}

/// The ranking and the verdict as text.
pub fn explanation_text(ex: &Explanation, top: usize) -> String {
    let mut s = String::new();
    if !ex.ranked.is_empty() {
        let _ = writeln!(
            s,
            "candidate effects, best first (score = evidence: {}):",
            scoring_basis(ex)
        );
    }
    for (i, r) in ex.ranked.iter().take(top).enumerate() {
        let params: Vec<String> = r.params.iter().map(param_text).collect();
        let rms: Vec<String> = ex
            .outputs
            .iter()
            .zip(&r.rms_after)
            .map(|(o, v)| format!("{} {}→{}", o.name, num(o.rms_before), num(*v)))
            .collect();
        // The score first, so a long name never pushes it out of its column; parameters and
        // RMS on the next line, wrapped at the text width.
        let _ = writeln!(
            s,
            "  {:>2}. score {:>7}  {}",
            i + 1,
            num(r.score),
            r.candidate.name
        );
        let _ = writeln!(
            s,
            "      {}; RMS {}",
            if params.is_empty() {
                "no parameters".to_string()
            } else {
                params.join(", ")
            },
            rms.join(", ")
        );
        if let Some(line) = qualitative_line(r) {
            let _ = writeln!(s, "      {line}");
        }
        if let Some(e) = &r.error {
            let _ = writeln!(s, "      fit failed: {e}");
        }
        if r.screened {
            let _ = writeln!(
                s,
                "      screened only: sized by one linearised step, not confirmed by a fit"
            );
        }
        if i == 0 && !r.equivalent.is_empty() {
            let names: Vec<&str> = (r.equivalent.iter())
                .map(|id| {
                    (ex.ranked.iter())
                        .find(|o| o.candidate.id == *id)
                        .map_or(id.as_str(), |o| o.candidate.name.as_str())
                })
                .collect();
            let _ = writeln!(
                s,
                "      fits exactly as well as: {} (as many parameters: the same physics said \
                 another way, or effects this recording cannot separate)",
                names.join("; ")
            );
        }
        if i == 0 && !r.indistinct.is_empty() {
            let _ = writeln!(
                s,
                "      this recording cannot tell it from: {} (as many parameters, scores within \
                 the significance margin)",
                r.indistinct.join("; ")
            );
        }
    }
    if ex.ranked.iter().take(top).any(|r| r.qualitative.is_some()) {
        let _ = writeln!(
            s,
            "  (signature agrees/disagrees: whether the model's qualitative diagnosis — fault \
             trees of the outputs' first deviations — points at the candidate; a hint, not part \
             of the score)"
        );
    }
    if !ex.ranked.is_empty() {
        let _ = writeln!(s, "margin to the runner-up: {}", num(ex.margin));
    }
    let places: Vec<_> = (ex.places.iter()).filter(|p| p.explained >= 0.05).collect();
    if !places.is_empty() {
        let _ = writeln!(
            s,
            "\nwhere the model fails (the missing effort or flow estimated at each place, and \
             the share of the outputs' error it removes):"
        );
        for p in places {
            let unit = unit_suffix(&p.unit);
            let _ = writeln!(
                s,
                "  {}: missing {} RMS {}{unit} ± {}{unit}, removes {:.0} % of the error",
                p.place,
                p.quantity.word(),
                num(p.rms),
                num(p.band),
                100.0 * p.explained
            );
            match &p.law {
                Some(l) => {
                    // A formula of the symbolic search is a shape, not a named law: say so.
                    let how = if l.has_formula() {
                        "regression on a typed library and on formulas a symbolic search \
                         built (the formula names no physical law)"
                    } else {
                        "regression on a typed library"
                    };
                    let _ = writeln!(
                        s,
                        "      its law ({how}, {:.0} % of it): {} = {}",
                        100.0 * l.explained,
                        p.quantity.word(),
                        l.describe()
                    );
                }
                None => {
                    let _ = writeln!(
                        s,
                        "      no law of the library, nor any formula of the symbolic search, explains it"
                    );
                }
            }
        }
    }
    let _ = writeln!(s, "\nverdict: {}", verdict_sentence(ex));
    let judged = !matches!(ex.verdict, Verdict::CannotJudge | Verdict::Interrupted);
    for o in &ex.outputs {
        if !judged {
            let _ = writeln!(
                s,
                "  {:<8} RMS {} {} (not judged)",
                o.name,
                num(o.rms_before),
                o.unit
            );
            continue;
        }
        let _ = writeln!(
            s,
            "  {:<8} RMS {} → {} {} (noise floor {}, {:.2}× the floor after)",
            o.name,
            num(o.rms_before),
            num(o.rms_after),
            o.unit,
            num(o.noise_floor),
            o.rms_after / o.noise_floor
        );
        for note in floor_notes(o) {
            let _ = writeln!(s, "           {note}");
        }
        if ex.verdict == Verdict::Partial && !o.remaining_windows.is_empty() {
            let w: Vec<String> = crate::residual::largest_windows(&o.remaining_windows, 5)
                .into_iter()
                .map(|w| format!("{}–{} s", num(w.start), num(w.end)))
                .collect();
            let more = match o.remaining_windows.len() {
                n if n > 5 => format!(" and {} with smaller peaks", n - 5),
                _ => String::new(),
            };
            let _ = writeln!(s, "           still fails at {}{more}", w.join(", "));
        }
    }
    let skip = usize::from(ex.verdict == Verdict::CannotJudge);
    for r in ex.reasons.iter().skip(skip) {
        let _ = writeln!(s, "  why: {r}");
    }
    for w in &ex.warnings {
        let _ = writeln!(s, "warning: {w}");
    }
    wrap_text(&s, TEXT_WIDTH)
}

/// What the judge made of an output's residual after the chosen effects beyond its RMS,
/// for the text and the page alike: taken for coloured noise above the white floor (and
/// why that is accepted), quantised.
fn floor_notes(o: &crate::explain::OutputSummary) -> Vec<String> {
    let mut notes = Vec::new();
    if let Some(j) = o.judgement.as_ref().filter(|j| j.coloured) {
        notes.push(format!(
            "taken for coloured noise of σ {}{} (correlation time {} samples, uncorrelated \
             with the inputs, unbiased): the white floor sees only its fast part",
            num(j.noise_sigma),
            unit_suffix(&o.unit),
            num(j.correlation_samples)
        ));
    }
    if let Some(q) = o.judgement.as_ref().and_then(|j| j.quantum) {
        notes.push(format!(
            "quantised in steps of {}{}: the floor includes their rounding error",
            num(q),
            unit_suffix(&o.unit)
        ));
    }
    notes
}

/// "[signature disagrees] measured i above the model …": the qualitative check of a
/// ranked candidate with its reason, `None` when the model made none.
pub fn qualitative_line(r: &crate::explain::RankedCandidate) -> Option<String> {
    let tag = match r.qualitative? {
        true => "[signature agrees]",
        false => "[signature disagrees]",
    };
    Some(if r.qualitative_reason.is_empty() {
        tag.to_string()
    } else {
        format!("{tag} {}", r.qualitative_reason)
    })
}

/// The HTML report of a comparison, with the explanation and the comparison
/// after the chosen effects when there is one.
pub fn build_report(
    before: &Comparison,
    explanation: Option<&Explanation>,
    after: Option<&Comparison>,
) -> Report {
    let mut summary = Vec::new();
    for o in &before.outputs {
        summary.push(format!(
            "{}: the model as given leaves an RMS error of {} {} ({:.1}× the noise floor of {} {}){}.",
            o.name,
            num(o.stats.rms),
            o.unit,
            o.rms_over_floor(),
            num(o.noise_floor),
            o.unit,
            if o.windows.is_empty() { ", and never leaves its band".to_string() } else { format!(", and leaves its band in {} window(s)", o.windows.len()) }
        ));
    }
    let verdict = explanation.map_or_else(
        || {
            if before.outputs.iter().all(|o| o.windows.is_empty()) {
                "Comparison only: the model never leaves its noise band.".to_string()
            } else {
                "Comparison only: the model fails where shaded below; run explain to find what is missing."
                    .to_string()
            }
        },
        verdict_sentence,
    );
    let mut table = vec![vec![
        "output".to_string(),
        "noise floor".to_string(),
        "RMS before".to_string(),
    ]];
    if after.is_some() {
        table[0].extend(["RMS after".to_string(), "after / floor".to_string()]);
    } else {
        table[0].push("RMS / floor".to_string());
    }
    for o in &before.outputs {
        let mut row = vec![
            format!("{} ({})", o.name, o.unit),
            num(o.noise_floor),
            num(o.stats.rms),
        ];
        match after {
            Some(a) => {
                let after_rms = a.output(&o.name).map(|a| a.stats.rms);
                row.push(after_rms.map_or("—".to_string(), num));
                row.push(
                    after_rms.map_or("—".to_string(), |r| format!("{:.2}", r / o.noise_floor)),
                );
            }
            None => row.push(format!("{:.2}", o.rms_over_floor())),
        }
        table.push(row);
    }
    if let Some(ex) = explanation {
        for c in &ex.chosen {
            let params: Vec<String> = c.params.iter().map(param_text).collect();
            // Names often say where already ("Coulomb friction on the shaft (1m)").
            let place = if c.candidate.name.contains(&c.candidate.acts_on) {
                String::new()
            } else {
                format!(" (acts on {})", c.candidate.acts_on)
            };
            summary.push(format!(
                "Chosen effect: {}{place}, {}.",
                c.candidate.name,
                params.join(", ")
            ));
            // The qualitative check runs on the ranking; the chosen effect's is there.
            let checked = ex.ranked.iter().find(|r| r.candidate.id == c.candidate.id);
            if let Some(r) = checked.filter(|r| r.qualitative.is_some()) {
                let word = if r.qualitative == Some(true) {
                    "agrees"
                } else {
                    "disagrees"
                };
                let why = if r.qualitative_reason.is_empty() {
                    String::new()
                } else {
                    format!(": {}", r.qualitative_reason)
                };
                summary.push(format!(
                    "The model's qualitative diagnosis (fault trees of the outputs' first \
                     deviations) {word} with it{why}. This is a hint, not part of the score."
                ));
            }
        }
    }
    if let Some(a) = after {
        for o in &a.outputs {
            summary.push(format!(
                "{} with the effect added: RMS error {} {} ({:.1}× the noise floor){}.",
                o.name,
                num(o.stats.rms),
                o.unit,
                o.rms_over_floor(),
                if o.windows.is_empty() {
                    ", never leaving its band".to_string()
                } else {
                    format!(", still leaving its band in {} window(s)", o.windows.len())
                }
            ));
        }
    }
    // Why a residual above the white floor was accepted (the text says it too).
    for o in explanation.iter().flat_map(|ex| &ex.outputs) {
        for note in floor_notes(o) {
            summary.push(format!("{}: the residual left is {note}.", o.name));
        }
    }
    let series = before
        .outputs
        .iter()
        .map(|o| SeriesPlot {
            title: o.name.clone(),
            unit: o.unit.clone(),
            t: before.t.clone(),
            measured: o.measured.clone(),
            before: o.predicted.clone(),
            after: after
                .and_then(|a| a.output(&o.name))
                .map(|a| a.predicted.clone()),
            // The residual strip beneath each plot shows the band and the failure windows,
            // so the page needs no separate residual plots.
            band: o.band,
            windows: o.windows.clone(),
        })
        .collect();
    let ranking = explanation.map_or_else(Vec::new, |ex| {
        let chosen: Vec<&str> = ex.chosen.iter().map(|c| c.candidate.id.as_str()).collect();
        ex.ranked
            .iter()
            .take(12)
            .filter(|r| r.score.is_finite())
            .map(|r| RankingBar {
                label: r.candidate.name.clone(),
                value: r.score,
                highlight: chosen.contains(&r.candidate.id.as_str()),
                note: {
                    let mut note = r
                        .params
                        .iter()
                        .map(param_text)
                        .collect::<Vec<_>>()
                        .join(", ");
                    // The qualitative check and its reason on a line of their own.
                    if let Some(q) = qualitative_line(r) {
                        note.push('\n');
                        note.push_str(&q);
                    }
                    note
                },
            })
            .collect()
    });
    Report {
        title: format!("modelgap: {} against the recording", before.model),
        summary_html_paragraphs: summary,
        verdict,
        table,
        series,
        residuals: Vec::new(),
        ranking,
        ranking_unit: "BIC evidence, with a penalty per fitted parameter".to_string(),
        extra_svgs: explanation.map_or_else(Vec::new, missing_plots),
    }
}

/// The missing effort at the places where the model fails (those removing at least 5 % of
/// the error, at most three), each with the law the screen found: as plots for the report.
fn missing_plots(ex: &Explanation) -> Vec<(String, String)> {
    (ex.missing.iter())
        .filter_map(|m| {
            let place = ex.places.iter().find(|p| p.location == m.location)?;
            (place.explained >= 0.05).then_some((m, place))
        })
        .take(3)
        .map(|(m, place)| {
            let law = place.law.as_ref();
            let caption = format!(
                "Where the model fails: the missing {} at {} estimated from the recording \
                 (a Kalman smoother with an unknown {} there), which removes {:.0} % of the \
                 outputs' error; {}",
                m.quantity.word(),
                m.place,
                m.quantity.word(),
                100.0 * place.explained,
                law.map_or(
                    "no law of the library, nor any formula of the symbolic search, explains it."
                        .to_string(),
                    |l| format!(
                        "the law found by regression ({:.0} % of it{}): {}.",
                        100.0 * l.explained,
                        if l.has_formula() {
                            "; a formula of the symbolic search, no named law"
                        } else {
                            ""
                        },
                        l.describe()
                    )
                )
            );
            (caption, crate::report::missing_svg(m, law))
        })
        .collect()
}

/// Writes `report.html` and `comparison.mcap` (measured, model before and
/// after, residuals, for Foxglove) into `dir` (created if needed).
///
/// # Errors
/// I/O errors with the path; invalid report data.
pub fn write_report_dir(
    dir: &Path,
    report: &Report,
    before: &Comparison,
    after: Option<&Comparison>,
) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| crate::CoreError::io(e, Some(dir)))?;
    write_html(report, &dir.join("report.html"))?;
    let names: Vec<String> = before.outputs.iter().map(|o| o.name.clone()).collect();
    let measured: Vec<Vec<f64>> = before.outputs.iter().map(|o| o.measured.clone()).collect();
    let predicted: Vec<Vec<f64>> = before.outputs.iter().map(|o| o.predicted.clone()).collect();
    let after_pred: Option<Vec<Vec<f64>>> = after.map(|a| {
        before
            .outputs
            .iter()
            .map(|o| {
                a.output(&o.name)
                    .map_or_else(|| o.predicted.clone(), |x| x.predicted.clone())
            })
            .collect()
    });
    // MCAP log times cannot be negative: shift so the first sample is at 0.
    let t0 = before.t.first().copied().unwrap_or(0.0);
    let t: Vec<f64> = before.t.iter().map(|x| x - t0).collect();
    let channels = ComparisonChannels {
        t: &t,
        names: &names,
        measured: &measured,
        before: &predicted,
        after: after_pred.as_deref(),
    };
    write_comparison_mcap(&channels, &dir.join("comparison.mcap"))
}

/// What a report shows: the comparison of the model as given, the explanation (if explain
/// ran), the effects added and the comparison of the model with them (if any were added),
/// the recording's name for the title, and a verdict sentence in place of the
/// explanation's (`fix --effect`).
pub struct ReportParts<'a> {
    /// The model as given against the recording.
    pub before: &'a Comparison,
    /// The explanation, if explain ran.
    pub explanation: Option<&'a Explanation>,
    /// The effects added, and the comparison of the model with them.
    pub after: Option<(&'a [Effect], &'a Comparison)>,
    /// The recording, as named in the title (its file name).
    pub data: &'a str,
    /// A verdict in place of the explanation's.
    pub verdict: Option<String>,
}

/// How the loop's results read for one kind of model: as text, as JSON and as the report.
/// Every method has the output-by-output reading of this module as its default; a model
/// whose outputs group (a cloth's marker coordinates, by marker and region) gives its own
/// through [`Model::story`](crate::Model::story). The command line and Python print through it, so that they
/// hold no branch per model kind.
pub trait Story: Send + Sync {
    /// Where the model fails (see [`comparison_text`]).
    fn comparison_text(&self, c: &Comparison) -> String {
        comparison_text(c)
    }

    /// The comparison as JSON (see [`crate::json::comparison_json`]).
    fn comparison_json(&self, c: &Comparison) -> serde_json::Value {
        crate::json::comparison_json(c)
    }

    /// Whether the comparison shows the model failing somewhere it can be judged (then
    /// explain has something to name).
    fn fails(&self, c: &Comparison) -> bool {
        c.outputs
            .iter()
            .any(|o| o.finding.is_none() && !o.windows.is_empty())
    }

    /// The ranking and the verdict (see [`explanation_text`]).
    fn explanation_text(&self, ex: &Explanation, top: usize) -> String {
        explanation_text(ex, top)
    }

    /// The explanation as JSON (see [`crate::json::explanation_json`]).
    fn explanation_json(&self, ex: &Explanation) -> serde_json::Value {
        crate::json::explanation_json(ex)
    }

    /// The error before → after (see [`before_after_text`]).
    fn before_after_text(&self, before: &Comparison, after: &Comparison) -> String {
        before_after_text(before, after)
    }

    /// Writes the report into `dir` (created if needed) and returns the page's path: by
    /// default `report.html` ([`build_report`]) and `comparison.mcap` for Foxglove
    /// ([`write_report_dir`]). `rec` is the recording the comparisons were made on.
    ///
    /// # Errors
    /// I/O errors naming the file; a model that cannot be simulated for the report.
    fn write_report(
        &self,
        dir: &Path,
        rec: &Recording,
        parts: &ReportParts<'_>,
    ) -> Result<PathBuf> {
        let _ = rec;
        let after = parts.after.map(|(_, c)| c);
        let mut report = build_report(parts.before, parts.explanation, after);
        report.title = format!("modelgap: {} against {}", parts.before.model, parts.data);
        if let Some(v) = &parts.verdict {
            report.verdict.clone_from(v);
        }
        write_report_dir(dir, &report, parts.before, after)?;
        Ok(dir.join("report.html"))
    }
}

/// The output-by-output reading of the loop's results: the [`Story`] of every model that
/// does not give its own.
#[derive(Clone, Copy, Debug, Default)]
pub struct PerOutput;

impl Story for PerOutput {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::{CompareOptions, compare};
    use crate::effect::{Candidate, EffectKind, EffectParam};
    use crate::explain::{ExplainOptions, explain};
    use crate::model::{Model, Prediction};
    use crate::recording::Signal;

    /// y = sin(2π t) with two candidates: an offset allowed only up to 0.1 (so a hidden
    /// offset of 0.3 drives its fit onto the bound) and a free dimensionless gain.
    struct Bounded;

    impl Model for Bounded {
        fn name(&self) -> String {
            "bounded".into()
        }
        fn outputs(&self) -> Vec<String> {
            vec!["y".into()]
        }
        fn predict_with(
            &self,
            rec: &Recording,
            effects: &[(&Candidate, &[f64])],
        ) -> Result<Prediction> {
            let y = rec
                .t()
                .iter()
                .map(|&t| {
                    let (mut a, mut y) = (1.0, 0.0);
                    for (c, v) in effects {
                        match c.id.as_str() {
                            "offset" => y += v[0],
                            "gain" => a += v[0],
                            _ => {}
                        }
                    }
                    y + a * (std::f64::consts::TAU * t).sin()
                })
                .collect();
            Ok(Prediction {
                names: vec!["y".into()],
                values: vec![y],
            })
        }
        fn candidates(&self) -> Vec<Candidate> {
            vec![
                Candidate {
                    id: "offset".into(),
                    name: "a sensor offset, allowed only up to 0.1".into(),
                    kind: EffectKind::MissingElement,
                    acts_on: "y".into(),
                    params: vec![EffectParam::new("offset", "V", 0.0, (0.0, 0.1), 0.05)],
                },
                Candidate {
                    id: "gain".into(),
                    name: "a gain error of the sensor".into(),
                    kind: EffectKind::MissingElement,
                    acts_on: "y".into(),
                    params: vec![EffectParam::new("gain", "1", 0.0, (-0.5, 0.5), 0.1)],
                },
            ]
        }
        fn with_effects(&self, _effects: &[Effect]) -> Result<Box<dyn Model>> {
            Ok(Box::new(Bounded))
        }
    }

    fn recording() -> Recording {
        let t: Vec<f64> = (0..1000).map(|k| f64::from(k) * 1e-3).collect();
        let mut g = crate::noise::Gaussian::new(3);
        let y = t
            .iter()
            .map(|&t| 0.3 + 1.1 * (std::f64::consts::TAU * t).sin() + 0.01 * g.sample())
            .collect();
        Recording::new(t, vec![Signal::new("y", y)]).unwrap()
    }

    fn param(name: &str, unit: &str, std_error: f64, at_bound: Option<&str>) -> FittedParam {
        FittedParam {
            name: name.into(),
            unit: unit.into(),
            value: 5.0,
            std_error,
            at_bound: at_bound.map(str::to_owned),
        }
    }

    #[test]
    fn a_value_on_a_bound_says_so_and_has_no_uncertainty() {
        assert_eq!(
            param_text(&param("R", "Ohm", 0.2, Some("upper"))),
            "R = 5 Ohm (at its upper bound)"
        );
        assert_eq!(param_text(&param("R", "Ohm", 0.2, None)), "R = 5 ± 0.2 Ohm");
        assert_eq!(
            param_text(&param("R", "Ohm", f64::INFINITY, None)),
            "R = 5 Ohm"
        );
        // No unit "1" after a dimensionless number.
        assert_eq!(param_text(&param("C_d", "1", 0.01, None)), "C_d = 5 ± 0.01");
        assert_eq!(
            param_text(&param("col", " 1 ", f64::INFINITY, None)),
            "col = 5"
        );
    }

    #[test]
    fn wrapped_text_keeps_every_word_and_short_lines() {
        let long = format!(
            "  {}\n    short line   with  alignment\n{}\n",
            "word ".repeat(60).trim_end(),
            "x".repeat(120)
        );
        let wrapped = wrap_text(&long, 40);
        let words = |s: &str| s.split_whitespace().map(str::to_owned).collect::<Vec<_>>();
        assert_eq!(words(&wrapped), words(&long));
        for line in wrapped.lines() {
            let n = line.chars().count();
            assert!(n <= 40 || !line.trim().contains(' '), "{n}: {line}");
        }
        // Lines that fit keep their spaces; continuations are indented deeper.
        assert!(wrapped.contains("\n    short line   with  alignment\n"));
        assert!(wrapped.lines().nth(1).unwrap().starts_with("      word"));
        assert_eq!(wrap_text("a b c\n", 4), "a b\n  c\n");
        // A number keeps its percent sign.
        assert_eq!(wrap_text("ab 12 %\n", 5), "ab 12 %\n");
    }

    // The CLI's text said why a residual 2.9× the white floor was accepted (coloured noise);
    // the report page did not.
    #[test]
    fn a_residual_taken_for_coloured_noise_is_said_so_in_the_text_and_on_the_page() {
        let rec = recording();
        let mut ex = explain(&Bounded, &rec, &ExplainOptions::default()).unwrap();
        let o = &mut ex.outputs[0];
        let j = o.judgement.as_mut().expect("judged");
        j.coloured = true;
        j.noise_sigma = 0.029;
        j.correlation_samples = 14.0;
        j.quantum = Some(0.2);
        let text = explanation_text(&ex, 3).replace('\n', " ");
        let words = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
        let text = words(&text);
        assert!(
            text.contains("taken for coloured noise of σ 0.029 (correlation time 14 samples"),
            "{text}"
        );
        // No space before the colon where the output has no unit.
        assert!(
            text.contains("quantised in steps of 0.2: the floor"),
            "{text}"
        );
        let before = compare(&Bounded, &rec, &CompareOptions::default()).unwrap();
        let report = build_report(&before, Some(&ex), None);
        let page = report.summary_html_paragraphs.join(" ");
        assert!(
            page.contains("y: the residual left is taken for coloured noise of σ 0.029 ("),
            "{page}"
        );
        assert!(
            page.contains("y: the residual left is quantised in steps of 0.2:"),
            "{page}"
        );
    }

    // Issue 16: fits that ended on a bound (beta = 5e-5 at 5× nominal) showed no ± and no
    // "at its bound"; a dimensionless value read "0.8006 1".
    #[test]
    fn explain_flags_a_fit_on_its_bound_in_text_json_and_report() {
        let rec = recording();
        let ex = explain(&Bounded, &rec, &ExplainOptions::default()).unwrap();
        let offset = ex
            .ranked
            .iter()
            .find(|r| r.candidate.id == "offset")
            .unwrap();
        let p = &offset.params[0];
        assert_eq!(p.at_bound.as_deref(), Some("upper"), "{p:?}");
        assert!(p.std_error.is_infinite());
        // A fit inside its bounds has its ± (alone on the menu, the gain is confirmed by a
        // fit; beside the offset it removes too little to be, and keeps the screen's size).
        let only_gain = ExplainOptions {
            only: vec!["gain".into()],
            ..ExplainOptions::default()
        };
        let ex_gain = explain(&Bounded, &rec, &only_gain).unwrap();
        let gain = (ex_gain.ranked.iter())
            .find(|r| r.candidate.id == "gain")
            .unwrap();
        assert_eq!(gain.params[0].at_bound, None, "{:?}", gain.params[0]);
        assert!(gain.params[0].std_error.is_finite());

        let text = explanation_text(&ex, 10);
        assert!(
            text.contains("offset = 0.1 V (at its upper bound)"),
            "{text}"
        );
        assert!(!text.contains("0.1 ±"), "{text}");
        assert!(text.contains("gain = ") && !text.contains(" 1;"), "{text}");
        for line in text.lines() {
            assert!(line.chars().count() <= TEXT_WIDTH, "{line}");
        }

        let json = crate::json::candidate_json(&ex, offset);
        assert_eq!(json["params"][0]["at_bound"], "upper");
        assert!(json["params"][0]["std_error"].is_null(), "{json}");
        let json = crate::json::candidate_json(&ex_gain, gain);
        assert!(json["params"][0]["at_bound"].is_null());
        assert!(json["params"][0]["std_error"].is_number());

        let before = compare(&Bounded, &rec, &CompareOptions::default()).unwrap();
        let report = build_report(&before, Some(&ex), None);
        let notes: Vec<&str> = report.ranking.iter().map(|b| b.note.as_str()).collect();
        assert!(
            notes.contains(&"offset = 0.1 V (at its upper bound)"),
            "{notes:?}"
        );
        let html = crate::report::render_html(&report);
        assert!(
            !html.contains(" 1<") && !html.contains(" 1,"),
            "unit 1 printed"
        );
    }
}
