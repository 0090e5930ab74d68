//! Ctrl-C, once for the whole command line: the first press sets a flag that long work
//! checks (explain stops between fits, a cloth run between steps) and says so on standard
//! error; nothing is written after it, and the command ends with [`Interrupted`] (exit code
//! 130). A second press ends the process at once, with the same code; every file is written
//! atomically, so even then no earlier good file is destroyed.

use std::sync::{Arc, OnceLock};

use modelgap::fit::Cancel;

/// The command was interrupted: nothing more was written. Exit code 130, as a shell
/// reports a process ended by SIGINT.
#[derive(Debug, thiserror::Error)]
#[error("interrupted (Ctrl-C): {0}")]
pub struct Interrupted(pub String);

static FLAG: OnceLock<Arc<Cancel>> = OnceLock::new();

/// The process's interrupt flag, with the Ctrl-C handler installed on first use.
pub fn flag() -> Arc<Cancel> {
    FLAG.get_or_init(|| {
        let flag = Arc::new(Cancel::new());
        let on_interrupt = flag.clone();
        // Fails only when another handler is installed; then Ctrl-C keeps its default action.
        let _ = ctrlc::set_handler(move || {
            if on_interrupt.is_cancelled() {
                std::process::exit(130);
            }
            on_interrupt.cancel();
            eprintln!(
                "\ninterrupting: stopping at the next chance, writing nothing \
                 (Ctrl-C again to quit at once)"
            );
        });
        flag
    })
    .clone()
}

/// Whether Ctrl-C was pressed.
pub fn is_set() -> bool {
    FLAG.get().is_some_and(|f| f.is_cancelled())
}

/// `Err(Interrupted)` when Ctrl-C was pressed: call it before writing anything.
///
/// # Errors
///
/// [`Interrupted`], saying what was not done.
pub fn check(what: &str) -> anyhow::Result<()> {
    if is_set() {
        return Err(Interrupted(what.to_owned()).into());
    }
    Ok(())
}
