//! `modelgap fix`: add the missing effect to the model. Explains the recording (or takes
//! the candidate the user names with `--effect`), builds the effect into the model, writes
//! the new model file, and compares both models with the recording so the error is seen to
//! fall.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use clap::Args;
use modelgap::story::verdict_sentence;
use modelgap::{Effect, EffectKind, Explanation, RankedCandidate, Verdict};

use super::BadInput;
use super::model::parse_whole;
use super::report::{
    LoopArgs, ReportParts, args_text_with_model, data_name, load_loop, print_notes, report_line,
    stop_if_interrupted,
};

/// Arguments of `modelgap fix`.
#[derive(Debug, Args)]
pub struct FixArgs {
    #[command(flatten)]
    pub common: LoopArgs,

    /// Add this candidate instead of explain's choice: its rank N (1 = the best) or its id
    /// (`coulomb@1m`, `deviation:R`)
    #[arg(long, value_name = "N|ID")]
    pub effect: Option<String>,

    /// Write the model with the effect(s) here (a bond-graph .toml, or a cloth scene .toml
    /// with the new term); never the input model
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,

    /// How many ranked candidates to print
    #[arg(long, value_name = "N", default_value_t = 5, value_parser = parse_whole, allow_negative_numbers = true)]
    pub top: usize,
}

/// Which candidate `--effect` names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Pick {
    /// A rank, from 1.
    Rank(usize),
    /// A candidate id.
    Id(String),
}

/// Parses `--effect` and checks it against the model's candidates: a rank
/// within them or an id one of them has. `what` names the model ("model",
/// "scene") in the message.
///
/// # Errors
/// [`BadInput`] naming the candidates when it matches none.
pub(super) fn checked_pick(
    effect: Option<&str>,
    model: &dyn modelgap::Model,
    what: &str,
) -> anyhow::Result<Option<Pick>> {
    let candidates = model.candidates();
    let pick = effect.map(Pick::parse);
    match &pick {
        Some(Pick::Rank(n)) if *n == 0 || *n > candidates.len() => {
            return Err(BadInput(format!(
                "--effect {n}: {what} {} offers {} candidate effects, ranked 1 to {}",
                model.name(),
                candidates.len(),
                candidates.len()
            ))
            .into());
        }
        Some(Pick::Id(id)) if !candidates.iter().any(|c| &c.id == id) => {
            return Err(BadInput(format!(
                "--effect {id}: {what} {} offers no candidate with that id; its candidates are {}",
                model.name(),
                candidates
                    .iter()
                    .map(|c| c.id.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
            .into());
        }
        _ => {}
    }
    Ok(pick)
}

impl Pick {
    pub(super) fn parse(text: &str) -> Pick {
        match text.trim().parse::<usize>() {
            Ok(n) => Pick::Rank(n),
            Err(_) => Pick::Id(text.trim().to_owned()),
        }
    }
}

/// Explains, adds the effect(s), writes the new model and prints the error before → after.
///
/// # Errors
///
/// Model and recording errors; [`BadInput`] for an `--effect` that names no candidate, an
/// `--out` that is the input model; a model that cannot simulate the recording or take the
/// effect; a file that cannot be written.
pub fn run(args: &FixArgs) -> anyhow::Result<()> {
    let loaded = load_loop(&args.common)?;
    check_out(&args.out, loaded.model_file.as_deref())?;
    let pick = checked_pick(args.effect.as_deref(), loaded.model.as_ref(), "model")?;
    print_notes(&loaded.notes);
    let story = loaded.story();
    let ex = loaded.explain(false)?;
    stop_if_interrupted(story, &ex, false, args.top)?;
    let mut out = format!(
        "model {} explaining {} ({} candidate effects fitted)\n",
        ex.model,
        args.common.data.display(),
        ex.ranked.len()
    );
    out.push_str(&story.explanation_text(&ex, args.top));

    let Some(Addition {
        added,
        shown,
        verdict: verdict_override,
    }) = what_to_add(&ex, pick.as_ref(), args, &mut out)?
    else {
        return super::print(&out);
    };
    let effects: Vec<Effect> = modelgap::explain::effects_of(&added);
    let fixed = loaded
        .model
        .with_effects(&effects)
        .context("building the effect into the model")?;
    let text = fixed.to_file_text().ok_or_else(|| {
        BadInput(format!(
            "model {} is not file-based: there is no model file to write",
            loaded.model.name()
        ))
    })?;
    super::interrupt::check("the new model was not written")?;
    write_checked(&args.out, &text)?;

    out.push('\n');
    for r in &added {
        out.push_str(&format!("added: {}\n", effect_line(r)));
        if r.candidate.kind == EffectKind::AbruptChange {
            out.push_str(
                "note: an abrupt change happens during a run: the model file holds it as a \
                 `[[changes]]` entry, which every run of the file makes\n",
            );
        }
    }
    out.push_str(&format!("wrote {}\n", args.out.display()));
    let before = loaded.compare(loaded.model.as_ref())?;
    let after = loaded.compare(fixed.as_ref())?;
    out.push_str("error before → after:\n");
    out.push_str(&story.before_after_text(&before, &after));
    if let Some(dir) = &args.common.report {
        let page = loaded.write_report(
            dir,
            &ReportParts {
                before: &before,
                explanation: Some(&shown),
                after: Some((&effects, &after)),
                data: &data_name(&args.common.data),
                verdict: verdict_override,
            },
        )?;
        out.push_str(&report_line(&page));
    }
    out.push_str(&format!(
        "next: `modelgap compare {}` holds the new model against the recording\n",
        args_text_with_model(&args.common, Some(&args.out))
    ));
    super::print(&out)
}

/// Writes the new model file atomically, after checking that it reads back as a model
/// (under its temporary name, so a file that does not read never replaces anything).
///
/// # Errors
///
/// The file cannot be written; it does not read back (a bug).
pub(super) fn write_checked(out: &Path, text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut file = modelgap::io::atomic::AtomicFile::create(out)
        .with_context(|| format!("writing the new model to {}", out.display()))?;
    file.write_all(text.as_bytes())
        .and_then(|()| file.flush())
        .with_context(|| format!("writing the new model to {}", out.display()))?;
    let written = file.temporary().to_string_lossy().into_owned();
    modelgap::load_model(&written, &modelgap::LoadOptions::default()).with_context(|| {
        format!(
            "the model for {} does not read back (a bug; please report it)",
            out.display()
        )
    })?;
    file.commit()
        .with_context(|| format!("writing the new model to {}", out.display()))
}

/// The candidate `--effect` names, with its rank from 1.
///
/// # Errors
///
/// [`BadInput`] when the rank or id is not in the ranking.
pub(super) fn picked<'a>(
    ex: &'a Explanation,
    pick: &Pick,
) -> anyhow::Result<(usize, &'a RankedCandidate)> {
    let found = match pick {
        Pick::Rank(n) => n
            .checked_sub(1)
            .and_then(|i| ex.ranked.get(i))
            .map(|r| (*n, r)),
        Pick::Id(id) => ex
            .ranked
            .iter()
            .enumerate()
            .find(|(_, r)| &r.candidate.id == id)
            .map(|(i, r)| (i + 1, r)),
    };
    found.ok_or_else(|| {
        BadInput(format!(
            "--effect: no such candidate in the ranking of {} candidates",
            ex.ranked.len()
        ))
        .into()
    })
}

/// What fix adds (see [`what_to_add`]).
pub(super) struct Addition {
    /// The effects to build into the model.
    pub(super) added: Vec<RankedCandidate>,
    /// The explanation as the report shows it (a pick as its choice).
    pub(super) shown: Explanation,
    /// For a pick, the verdict sentence that replaces explain's.
    pub(super) verdict: Option<String>,
}

/// What fix adds: explain's choice, or the user's `--effect` pick; with the
/// explanation as the report shows it (the pick as its choice) and, for a
/// pick, the verdict sentence that replaces explain's. `None` when there is
/// nothing to add, said in `out`, as is a partial explanation's note.
/// Shared by bond-graph and cloth `fix`.
///
/// # Errors
///
/// [`BadInput`] when the pick is not in the ranking; an error when its fit
/// failed.
pub(super) fn what_to_add(
    ex: &Explanation,
    pick: Option<&Pick>,
    args: &FixArgs,
    out: &mut String,
) -> anyhow::Result<Option<Addition>> {
    let Some(p) = pick else {
        if ex.chosen.is_empty() {
            out.push_str(&format!(
                "\nnothing to add ({}): {} not written\n",
                ex.verdict,
                args.out.display()
            ));
            return Ok(None);
        }
        if ex.verdict == Verdict::Partial {
            out.push_str(
                "\nnote: a partial explanation: the effect below lowers the error but does not \
                 reach the noise floor\n",
            );
        }
        return Ok(Some(Addition {
            added: ex.chosen.clone(),
            shown: ex.clone(),
            verdict: None,
        }));
    };
    let (rank, r) = picked(ex, p)?;
    if let Some(e) = &r.error {
        anyhow::bail!(
            "the fit of {} (--effect {}) failed, so it cannot be added: {e}",
            r.candidate.name,
            args.effect.as_deref().unwrap_or_default()
        );
    }
    let mut shown = ex.clone();
    shown.chosen = vec![r.clone()];
    let verdict = format!(
        "Added by hand (--effect): {}, ranked {rank} of {}. explain's own verdict: {}",
        r.candidate.name,
        ex.ranked.len(),
        verdict_sentence(ex)
    );
    Ok(Some(Addition {
        added: vec![r.clone()],
        shown,
        verdict: Some(verdict),
    }))
}

/// A fitted effect in one line: name, where it acts, parameters ± standard error.
pub fn effect_line(r: &RankedCandidate) -> String {
    let params: Vec<String> = r.params.iter().map(modelgap::story::param_text).collect();
    // Names often say where already: "Coulomb friction on the shaft (1m)".
    if r.candidate.name.contains(&r.candidate.acts_on) {
        format!("{}: {}", r.candidate.name, params.join(", "))
    } else {
        format!(
            "{} (acts on {}): {}",
            r.candidate.name,
            r.candidate.acts_on,
            params.join(", ")
        )
    }
}

/// Refuses an `--out` that is the input model file, a directory, or in a directory that
/// does not exist.
///
/// # Errors
///
/// [`BadInput`] naming the path.
pub(super) fn check_out(out: &Path, model_file: Option<&Path>) -> anyhow::Result<()> {
    super::model::check_out_dir("--out", out)?;
    if out.is_dir() {
        return Err(BadInput(format!(
            "--out {} is a directory: give the new model file's name",
            out.display()
        ))
        .into());
    }
    if let (Some(model), true) = (model_file, out.exists()) {
        let same = match (std::fs::canonicalize(model), std::fs::canonicalize(out)) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        };
        if same {
            return Err(BadInput(format!(
                "--out {} is the input model file: write the new model to another file",
                out.display()
            ))
            .into());
        }
    }
    Ok(())
}
