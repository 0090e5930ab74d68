//! The model every `bond` subcommand takes: `--model` (a file or a built-in name) and
//! `--set NAME=VALUE`; the steady state that `--steady-start` starts from; and what the
//! options of every subcommand share: number parsers whose messages say what was expected,
//! and reading a recording given by an option (`--data`, `--inputs`).

use std::path::Path;

use anyhow::Context as _;
use clap::Args;
use modelgap::bond::BondGraph;
use modelgap::bond::compiled::CompiledModel;
use modelgap::bond::file::read_model_path;
use modelgap::bond::library::{self, BUILTINS};
use modelgap::io::csv::CsvOptions;
use modelgap::io::read_recording_path_with;
use modelgap::{LoadOptions, Recording};

use super::BadInput;
use super::format::num;

/// Which model to use and which of its values to change.
#[derive(Debug, Args)]
pub struct ModelArgs {
    /// Model file (.toml) or built-in model name (dc-motor, buck-motor); compare, explain and
    /// fix also take a cloth scene file (a .toml with a [cloth] table)
    #[arg(long, value_name = "MODEL")]
    pub model: String,

    /// Set a parameter, or an input's default value, before anything else (repeatable)
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_assignment)]
    pub set: Vec<Assignment>,
}

impl ModelArgs {
    /// The loader's options: these `--set`s, then the start and input hold given (`None`:
    /// chosen from the recording).
    pub fn load_options(
        &self,
        steady_start: bool,
        hold: Option<modelgap::load::Hold>,
    ) -> LoadOptions {
        LoadOptions {
            set: self.set.iter().map(|a| (a.name.clone(), a.value)).collect(),
            steady_start,
            hold,
            free: Vec::new(),
        }
    }
}

/// How a CSV recording is read: files as other tools export them (pandas, R, spreadsheets)
/// mostly read as they are; these say what cannot be detected. `--time` also applies to
/// Parquet recordings.
#[derive(Debug, Default, Args)]
pub struct CsvArgs {
    /// CSV and Parquet recordings: the time column, named as in the header, with or without
    /// its unit (default: the column `t`, else the one named `t` with a unit, else the one
    /// named `t` or `time` in any case, with any unit; of several, one whose unit is no time
    /// unit, such as `T [degC]`, is not time)
    #[arg(long = "time", value_name = "COL")]
    pub time: Option<String>,

    /// CSV recordings: the cell separator, such as `;` or `tab` (default: `,`, or `;` or a tab
    /// when the header has one and no `,`)
    #[arg(long, value_name = "SEP", value_parser = parse_delimiter)]
    pub delimiter: Option<u8>,

    /// CSV recordings: numbers are written with a decimal comma, 1,5 for 1.5 (default:
    /// detected when cells are separated by `;` or tabs)
    #[arg(long)]
    pub decimal_comma: bool,
}

impl CsvArgs {
    /// The reader's options.
    pub fn options(&self) -> CsvOptions {
        CsvOptions {
            time: self.time.clone(),
            delimiter: self.delimiter,
            decimal_comma: self.decimal_comma.then_some(true),
        }
    }

    /// The options as they would be typed again, for the "next:" hints.
    pub fn to_args(&self) -> Vec<String> {
        let quote = |t: &str| {
            if t.is_empty()
                || t.contains(|c: char| !(c.is_ascii_alphanumeric() || "_.-".contains(c)))
            {
                format!("'{}'", t.replace('\'', "'\\''"))
            } else {
                t.to_owned()
            }
        };
        let mut args = Vec::new();
        if let Some(time) = &self.time {
            args.push(format!("--time {}", quote(time)));
        }
        if let Some(d) = self.delimiter {
            let sep = if d == b'\t' {
                "tab".to_owned()
            } else {
                quote(&char::from(d).to_string())
            };
            args.push(format!("--delimiter {sep}"));
        }
        if self.decimal_comma {
            args.push("--decimal-comma".to_owned());
        }
        args
    }
}

/// Parses `--delimiter`: one ASCII character, or `tab`.
fn parse_delimiter(text: &str) -> Result<u8, String> {
    match text {
        "tab" | "\\t" | "\t" => Ok(b'\t'),
        _ if text.len() == 1 && text.is_ascii() => Ok(text.as_bytes()[0]),
        _ => Err(format!(
            "expected one character, such as `;` or `,`, or `tab`; found `{text}`"
        )),
    }
}

/// A `NAME=VALUE` pair of `--set`.
#[derive(Clone, Debug, PartialEq)]
pub struct Assignment {
    /// The parameter or input.
    pub name: String,
    /// Its new value (finite).
    pub value: f64,
}

/// Parses `NAME=VALUE` with a finite number as the value.
pub fn parse_assignment(text: &str) -> Result<Assignment, String> {
    let (name, value) = text
        .split_once('=')
        .ok_or_else(|| format!("expected NAME=VALUE, found `{text}`"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(format!("expected NAME=VALUE, found no name in `{text}`"));
    }
    let value = parse_number(value).map_err(|e| format!("{e} for `{name}`"))?;
    Ok(Assignment {
        name: name.to_owned(),
        value,
    })
}

/// Parses a finite number; the error says what was found.
pub fn parse_number(text: &str) -> Result<f64, String> {
    let text = text.trim();
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("`{text}` is not a finite number")),
        Err(_) => Err(format!("`{text}` is not a number")),
    }
}

/// Parses a finite number > 0 in `unit` (the error names the unit; clap puts the option's
/// name in front of it).
fn parse_positive_in(text: &str, unit: &str) -> Result<f64, String> {
    let v = parse_number(text)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("must be positive, found {v}{unit}"))
    }
}

/// Parses a finite number > 0.
pub fn parse_positive(text: &str) -> Result<f64, String> {
    parse_positive_in(text, "")
}

/// Parses a duration in seconds > 0.
pub fn parse_seconds(text: &str) -> Result<f64, String> {
    parse_positive_in(text, " s")
}

/// Parses a rate in Hz > 0.
pub fn parse_hertz(text: &str) -> Result<f64, String> {
    parse_positive_in(text, " Hz")
}

/// Parses a whole number ≥ 1 (a count); a negative or fractional number is named as such.
pub fn parse_count(text: &str) -> Result<usize, String> {
    let text = text.trim();
    match text.parse::<usize>() {
        Ok(0) => Err("must be at least 1, found 0".to_owned()),
        Ok(n) => Ok(n),
        Err(_) => match text.parse::<f64>() {
            Ok(v) if v < 1.0 => Err(format!("must be at least 1, found {text}")),
            Ok(_) => Err(format!("must be a whole number, found {text}")),
            Err(_) => Err(format!("expected a whole number >= 1, found `{text}`")),
        },
    }
}

/// Parses a whole number ≥ 0 (how many lines to print); a negative or fractional number is
/// named as such.
pub fn parse_whole(text: &str) -> Result<usize, String> {
    let text = text.trim();
    text.parse::<usize>()
        .map_err(|_| match text.parse::<f64>() {
            Ok(v) if v < 0.0 => format!("must be 0 or more, found {text}"),
            Ok(_) => format!("must be a whole number, found {text}"),
            Err(_) => format!("expected a whole number >= 0, found `{text}`"),
        })
}

/// Refuses a file to write (`--out`) whose directory does not exist, before any work.
///
/// # Errors
///
/// [`BadInput`] naming the option, the path and the missing directory.
pub fn check_out_dir(option: &str, path: &Path) -> anyhow::Result<()> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() && !dir.is_dir() => Err(BadInput(format!(
            "{option} {}: directory {} does not exist",
            path.display(),
            dir.display()
        ))
        .into()),
        _ => Ok(()),
    }
}

/// Refuses a report directory (`--report`) that is an existing file, before any work.
///
/// # Errors
///
/// [`BadInput`] naming the option and the path.
pub fn check_report_dir(option: &str, dir: &Path) -> anyhow::Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(BadInput(format!(
            "{option} {} is a file: give a directory (report.html and comparison.mcap are \
             written into it)",
            dir.display()
        ))
        .into());
    }
    Ok(())
}

/// Reads the recording an option names (`--data`, `--inputs`): a missing file or a
/// directory is refused with the option and the path.
///
/// # Errors
///
/// [`BadInput`] for a path that does not exist or is a directory; the reader's errors (with
/// the line and column) under the context `reading <what> <path>`.
pub fn read_recording_arg(option: &str, what: &str, path: &Path) -> anyhow::Result<Recording> {
    read_recording_arg_with(option, what, path, &CsvArgs::default())
}

/// Reads the recording an option names, as [`read_recording_arg`] does, a CSV file with the
/// `--time`, `--delimiter` and `--decimal-comma` given; the reader's notes (an index column
/// left out, a unit row read) go to standard error.
///
/// # Errors
///
/// As [`read_recording_arg`].
pub fn read_recording_arg_with(
    option: &str,
    what: &str,
    path: &Path,
    csv: &CsvArgs,
) -> anyhow::Result<Recording> {
    if path.is_dir() {
        return Err(BadInput(format!(
            "{option} {} is a directory: give a recording file (.csv, .mcap or .parquet)",
            path.display()
        ))
        .into());
    }
    if !path.exists() {
        return Err(BadInput(format!(
            "{option}: {what} file {} not found",
            path.display()
        ))
        .into());
    }
    let (rec, notes) = read_recording_path_with(path, &csv.options())
        .with_context(|| format!("reading {what} {}", path.display()))?;
    super::report::print_notes(&notes);
    Ok(rec)
}

/// The built-in model names, comma-separated.
pub fn builtin_names() -> String {
    BUILTINS
        .iter()
        .map(|(name, _)| *name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Loads the model: the file at `--model` if there is one, else the built-in of that name;
/// then applies every `--set`.
///
/// # Errors
///
/// A missing file or unknown built-in (the message lists the built-ins), a model file that
/// does not read, a `--set` of an unknown name.
pub fn load(args: &ModelArgs) -> anyhow::Result<BondGraph> {
    let path = Path::new(&args.model);
    // A directory that happens to share a built-in's name does not hide the built-in.
    if path.is_dir() && library::builtin(&args.model).is_err() {
        return Err(BadInput(format!(
            "--model {} is a directory: give a model file (.toml) or a built-in model ({})",
            path.display(),
            builtin_names()
        ))
        .into());
    }
    let mut g = if path.is_file() {
        read_model_path(path).with_context(|| format!("loading model {}", path.display()))?
    } else if looks_like_path(&args.model) {
        return Err(BadInput(format!(
            "--model: model file {} not found (built-in models: {})",
            path.display(),
            builtin_names()
        ))
        .into());
    } else {
        library::builtin(&args.model).with_context(|| {
            format!(
                "`{}` is neither a model file nor a built-in model",
                args.model
            )
        })?
    };
    for a in &args.set {
        g.set_param(&a.name, a.value)
            .with_context(|| format!("applying --set {}={}", a.name, num(a.value)))?;
    }
    Ok(g)
}

/// True for text that names a file rather than a built-in model.
fn looks_like_path(text: &str) -> bool {
    text.contains('/') || text.contains('\\') || text.to_ascii_lowercase().ends_with(".toml")
}

/// The steady state of `g` under constant inputs `u` (in the model's input order), by
/// Newton's method ([`CompiledModel::steady_state`]).
///
/// # Errors
///
/// Model errors; [`BadInput`] when the model has no steady state there (a singular Jacobian,
/// such as a free integrator, or no convergence).
pub fn steady_state(g: &BondGraph, u: &[f64]) -> anyhow::Result<Vec<f64>> {
    let model = CompiledModel::new(g)?;
    // A law that is NaN where Newton starts is named, not reported as "no convergence".
    model.check_finite(0.0, &vec![0.0; model.n_states()], u, true)?;
    model
        .steady_state(u, None)
        .map_err(|e| BadInput(format!("model {} has no steady state: {e}", g.name)).into())
}

/// The outputs of `g` at state `x` and inputs `u`, in the model's output order.
///
/// # Errors
///
/// Model errors.
pub fn outputs_at(g: &BondGraph, x: &[f64], u: &[f64]) -> anyhow::Result<Vec<f64>> {
    let model = CompiledModel::new(g)?;
    let mut scratch = model.scratch();
    model.eval(0.0, x, u, &mut scratch);
    let mut y = vec![0.0; model.n_outputs()];
    model.read_outputs(&scratch, &mut y);
    Ok(y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn assignment_parses_and_names_the_bad_pair() {
        assert_eq!(
            parse_assignment("R=1.2"),
            Ok(Assignment {
                name: "R".into(),
                value: 1.2
            })
        );
        let e = parse_assignment("X=abc").unwrap_err();
        assert!(e.contains("`abc`") && e.contains("`X`"), "{e}");
        assert!(parse_assignment("R").is_err());
        assert!(parse_assignment("=1").is_err());
        assert!(parse_assignment("R=inf").is_err());
    }

    #[test]
    fn unknown_model_lists_the_builtins() {
        let args = ModelArgs {
            model: "no-such-motor".into(),
            set: vec![],
        };
        let e = load(&args).unwrap_err();
        let chain = format!("{e:#}");
        assert!(
            chain.contains("dc-motor") && chain.contains("buck-motor"),
            "{chain}"
        );
        let args = ModelArgs {
            model: "missing/model.toml".into(),
            set: vec![],
        };
        let chain = format!("{:#}", load(&args).unwrap_err());
        assert!(chain.contains("missing/model.toml") && chain.contains("dc-motor"));
    }

    #[test]
    fn set_changes_a_parameter_and_rejects_unknown_names() {
        let mut args = ModelArgs {
            model: "dc-motor".into(),
            set: vec![parse_assignment("R=2").unwrap()],
        };
        assert_eq!(load(&args).unwrap().param("R").unwrap(), 2.0);
        args.set = vec![parse_assignment("X=1").unwrap()];
        let chain = format!("{:#}", load(&args).unwrap_err());
        assert!(chain.contains("X=1") && chain.contains("beta"), "{chain}");
    }

    #[test]
    fn steady_state_of_the_dc_motor_matches_closed_form() {
        let g = library::dc_motor();
        let x = steady_state(&g, &[12.0, 0.0]).unwrap();
        let y = outputs_at(&g, &x, &[12.0, 0.0]).unwrap();
        // ω = kV / (Rβ + k²); the linear model is solved in one Newton step.
        let omega = 0.05 * 12.0 / (1e-5 + 0.0025);
        assert!((y[1] - omega).abs() < 1e-6 * omega, "{y:?}");
    }

    #[test]
    fn steady_state_of_the_buck_motor_holds_still() {
        // The switch multiplies two inputs (m · Vs): the model is not affine in its inputs,
        // so the steady state must come from f(x, u) = 0 itself.
        let g = library::buck_motor();
        let u: Vec<f64> = g.inputs().values().map(|i| i.default).collect();
        let x = steady_state(&g, &u).unwrap();
        let model = CompiledModel::new(&g).unwrap();
        let mut scratch = model.scratch();
        let mut dx = vec![0.0; model.n_states()];
        model.eval(0.0, &x, &u, &mut scratch);
        model.read_derivatives(&scratch, &mut dx);
        assert!(dx.iter().all(|d| d.abs() < 1e-6), "{dx:?}");
    }
}
