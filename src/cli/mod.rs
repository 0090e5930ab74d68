//! The `modelgap` command line: argument definitions (clap derive), dispatch, exit codes.
//!
//! Each subcommand sits in its own module and is a library call plus formatting:
//! [`model`] loads the model every `bond` subcommand takes, [`format`] prints numbers and
//! matrices, [`noise`] is the seeded Gaussian generator of `simulate --noise`. The
//! measurement loop is [`compare`], [`explain`] and [`fix`], with what they share (loading a
//! model with a recording, the progress bar, the report, JSON) in [`report`]; [`demo`] tells
//! its story on bundled data.

mod arr;
mod bench;
mod causality;
mod cloth;
mod compare;
mod demo;
mod diagnose;
mod equations;
mod explain;
mod fit;
mod fix;
mod format;
mod graph;
mod interrupt;
mod model;
mod noise;
mod report;
mod simulate;
mod table7;

use std::io::Write as _;

use clap::{Parser, Subcommand};
use modelgap::cloth::ClothError;
use modelgap::{BondError, CoreError};

/// Hold physical models against measurements: see where a model fails, learn which physical
/// effect is missing, add it and watch the error fall; bond graphs with fault diagnosis.
#[derive(Debug, Parser)]
#[command(name = "modelgap", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The top-level commands.
#[derive(Debug, Subcommand)]
enum Command {
    /// Hold a model against a recording: error per output, noise floor, failure windows
    Compare(compare::CompareArgs),
    /// Name the physical effect the model is missing: candidates fitted, ranked, a verdict
    Explain(explain::ExplainArgs),
    /// Add the missing effect: write the new model file and show the error before -> after
    Fix(fix::FixArgs),
    /// Calibrate the model's free parameters and initial states on a recording and write the
    /// calibrated model file
    Fit(fit::FitArgs),
    /// Bond graphs: equations, simulation, causal graph, causality, diagnosis
    #[command(subcommand)]
    Bond(BondCommand),
    /// Cloth: run a scene and write its trajectory, time the solver
    #[command(subcommand)]
    Cloth(cloth::ClothCommand),
    /// Run the main demonstration: the measurement loop on a bundled motor recording with a
    /// hidden effect, then on a bundled cloth marker recording, then the DC-motor paper's
    /// Table 7 diagnosis
    Demo(demo::DemoArgs),
}

/// The `modelgap bond` subcommands.
#[derive(Debug, Subcommand)]
enum BondCommand {
    /// Print the causal equations, the state space, eigenvalues and the causality
    Equations(equations::EquationsArgs),
    /// Simulate a model and write its inputs and outputs as CSV or MCAP
    Simulate(simulate::SimulateArgs),
    /// Print the causal graph as Graphviz DOT (or its antecedents/consequents table)
    Graph(graph::GraphArgs),
    /// Print the causal stroke of every bond and the causality of the storage elements
    Causality(causality::CausalityArgs),
    /// Diagnose a recording: residuals, fault trees, signatures, hypothesis set
    Diagnose(diagnose::DiagnoseArgs),
    /// Analytical redundancy relations, fault signature matrix, detectability and isolability
    Arr(arr::ArrArgs),
    /// The paper's Table 7: every ±20 % fault of the buck-motor simulated, detected, diagnosed
    Table7(table7::Table7Args),
    /// Time the simulator on the reference runs (DC motor 0-4 s, PWM buck-motor 0-1 s)
    Bench(bench::BenchArgs),
}

/// Runs the command the arguments name.
///
/// # Errors
///
/// Whatever the command meets, with context naming the file or model concerned.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    // Ctrl-C from here on sets a flag that long work checks (see `interrupt`).
    let _ = interrupt::flag();
    match cli.command {
        Command::Bond(BondCommand::Equations(args)) => equations::run(&args),
        Command::Bond(BondCommand::Simulate(args)) => simulate::run(&args),
        Command::Bond(BondCommand::Graph(args)) => graph::run(&args),
        Command::Bond(BondCommand::Causality(args)) => causality::run(&args),
        Command::Bond(BondCommand::Diagnose(args)) => diagnose::run(&args),
        Command::Bond(BondCommand::Arr(args)) => arr::run(&args),
        Command::Bond(BondCommand::Table7(args)) => table7::run(&args),
        Command::Bond(BondCommand::Bench(args)) => bench::run(&args),
        Command::Cloth(command) => cloth::run(&command),
        Command::Compare(args) => compare::run(&args),
        Command::Explain(args) => explain::run(&args),
        Command::Fix(args) => fix::run(&args),
        Command::Fit(args) => fit::run(&args),
        Command::Demo(args) => demo::run(&args),
    }
}

/// An input the user can fix: a missing file, a value out of range, a name that does not
/// exist. The process exits with code 2 for it, as for argument errors.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BadInput(pub String);

/// Exit code 2: the input is bad (arguments, model, data); 1: anything else failed.
const EXIT_BAD_INPUT: u8 = 2;
/// Exit code 1: the command failed for another reason (a solver, a write).
const EXIT_FAILURE: u8 = 1;
/// Exit code 130: interrupted by Ctrl-C (as a shell reports SIGINT).
const EXIT_INTERRUPTED: u8 = 130;

/// The process exit code for an error: 2 when the user's input is at fault (a bad argument,
/// a model or data file that is missing or malformed, an unknown name), 1 otherwise.
pub fn exit_code(err: &anyhow::Error) -> u8 {
    for cause in err.chain() {
        if cause.downcast_ref::<interrupt::Interrupted>().is_some() {
            return EXIT_INTERRUPTED;
        }
        if cause.downcast_ref::<BadInput>().is_some() {
            return EXIT_BAD_INPUT;
        }
        if let Some(e) = cause.downcast_ref::<BondError>() {
            return bond_exit_code(e);
        }
        if let Some(e) = cause.downcast_ref::<CoreError>() {
            return core_exit_code(e);
        }
        if let Some(e) = cause.downcast_ref::<ClothError>() {
            return cloth_exit_code(e);
        }
        if let Some(e) = cause.downcast_ref::<modelgap::Error>() {
            return match e {
                modelgap::Error::Core(e) => core_exit_code(e),
                modelgap::Error::Bond(e) => bond_exit_code(e),
                modelgap::Error::Cloth(e) => cloth_exit_code(e),
                modelgap::Error::Set { source, .. } => bond_exit_code(source),
                _ => EXIT_BAD_INPUT,
            };
        }
    }
    EXIT_FAILURE
}

fn cloth_exit_code(e: &ClothError) -> u8 {
    match e {
        ClothError::Core(core) => core_exit_code(core),
        // A simulation that blew up is a failure; scene and marker files are fixed by
        // changing the input.
        ClothError::NonFinite { .. } | ClothError::Diverged { .. } => EXIT_FAILURE,
        _ => EXIT_BAD_INPUT,
    }
}

fn bond_exit_code(e: &BondError) -> u8 {
    match e {
        // The solver gave up (step size, step budget, a singular matrix): a failure.
        BondError::Ode(_) => EXIT_FAILURE,
        BondError::Core(core) => core_exit_code(core),
        // A parameter the element cannot have, a law that is NaN at the start, a run past a
        // limit: fixed by changing the input.
        BondError::UnphysicalParameter { .. }
        | BondError::LawNotFinite { .. }
        | BondError::TooLarge { .. } => EXIT_BAD_INPUT,
        // The adaptive solvers control their error and the exact one is exact: a state that
        // stops being finite is the solution of the model as given (its values, its inputs)
        // running away (`--set k=1e300`), not a solver failure.
        BondError::NonFiniteState { .. } | BondError::NonFiniteOutput { .. } => EXIT_BAD_INPUT,
        // Model files, names, causality, inputs, options: all fixed by changing the input.
        _ => EXIT_BAD_INPUT,
    }
}

fn core_exit_code(e: &CoreError) -> u8 {
    // A model's own error through the loop's seam keeps its crate's code.
    if let Some(domain) = e.model_error() {
        if let Some(b) = domain.downcast_ref::<BondError>() {
            return bond_exit_code(b);
        }
        if let Some(c) = domain.downcast_ref::<ClothError>() {
            return cloth_exit_code(c);
        }
    }
    match e {
        CoreError::McapWrite { .. } => EXIT_FAILURE,
        _ => EXIT_BAD_INPUT,
    }
}

/// True when the error is a write to a closed pipe (`modelgap ... | head`).
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Writes `text` to standard output. A closed pipe surfaces as an error that
/// [`is_broken_pipe`] recognises, instead of a panic as with `print!`.
fn print(text: &str) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory as _;

    use super::*;

    /// Issue 12: compare, explain and fix are written once against `dyn Model`; what
    /// differs between model kinds lives in the library (`modelgap::load`, each model's
    /// `Story`), not in these modules.
    #[test]
    fn loop_commands_hold_no_branch_per_model_kind() {
        let sources = [
            ("compare.rs", include_str!("compare.rs")),
            ("explain.rs", include_str!("explain.rs")),
            ("fix.rs", include_str!("fix.rs")),
            ("report.rs", include_str!("report.rs")),
        ];
        let kind_words = [
            "modelgap::bond",
            "modelgap::cloth",
            "BondModel",
            "ClothModel",
            "Scene",
            "BondError",
            "ClothError",
        ];
        for (file, text) in sources {
            for word in kind_words {
                assert!(
                    !text.contains(word),
                    "src/cli/{file} names `{word}`: a model-kind branch belongs in the library"
                );
            }
        }
    }

    #[test]
    fn clap_definitions_are_consistent() {
        Cli::command().debug_assert();
    }

    #[test]
    fn bad_input_and_model_errors_exit_with_2_solver_errors_with_1() {
        let e = anyhow::Error::new(BadInput("no such file".into())).context("reading x.csv");
        assert_eq!(exit_code(&e), 2);
        let e = anyhow::Error::new(BondError::UnknownModel {
            name: "x".into(),
            known: "dc-motor".into(),
        });
        assert_eq!(exit_code(&e), 2);
        let e = anyhow::Error::new(BondError::BadOptions("x".into())).context("simulating");
        assert_eq!(exit_code(&e), 2);
        let e = anyhow::anyhow!("something else");
        assert_eq!(exit_code(&e), 1);
        // Issue 11: a parameter the user set badly is bad input, however it shows.
        let e = anyhow::Error::new(BondError::UnphysicalParameter {
            param: "L".into(),
            expression: false,
            element: "L".into(),
            kind: modelgap::bond::ElementKind::I,
            quantity: "inductance, H".into(),
            expected: "positive",
            value: 0.0,
        })
        .context("applying --set L=0");
        assert_eq!(exit_code(&e), 2);
        let e = anyhow::Error::new(BondError::NonFiniteState {
            state: "p3".into(),
            what: "the momentum of I:L".into(),
            t: 0.001,
        });
        assert_eq!(exit_code(&e), 2);
        let e = anyhow::Error::new(BondError::Ode(
            modelgap::bond::ode::OdeError::TooManySteps {
                t: 1.0,
                max_steps: 10,
            },
        ));
        assert_eq!(exit_code(&e), 1);
    }

    #[test]
    fn broken_pipe_is_recognised_through_context() {
        let e = anyhow::Error::new(std::io::Error::from(std::io::ErrorKind::BrokenPipe))
            .context("printing");
        assert!(is_broken_pipe(&e));
        assert!(!is_broken_pipe(&anyhow::anyhow!("other")));
    }
}
