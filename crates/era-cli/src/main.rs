//! The `era` command line. [`args`] (clap, importing nothing of the crate) →
//! [`config`] (typed settings, a file per verb) → [`commands`] (one verb each: read
//! with [`input`], call the library through [`work`], hand the result to [`output`]:
//! every file written, the figures, the report, the terminal). Nothing imports a
//! command but `batch`, which runs `identify` and `oma`.
//!
//! Exit codes: 0 success, 2 bad input or usage (the message names the file, line,
//! flag or value), 1 internal failure. No panic reaches the user: one is caught and
//! reported as an internal error.

mod args;
mod commands;
mod config;
mod error;
mod input;
mod output;
mod work;

use clap::Parser;
use error::UsageError;
use std::process::ExitCode;

/// 2 when the first cause of era's own ([`era::error::InputError`]) is the user's (bad
/// data, bad flag, unreadable or unwritable file), 1 otherwise: each error type decides
/// by its `is_input_error()`.
fn exit_code(err: &anyhow::Error) -> u8 {
    match err.chain().find_map(input_error) {
        Some(true) => 2,
        Some(false) | None => 1,
    }
}

/// `cause`'s `is_input_error()` when it is one of era's errors.
fn input_error(cause: &(dyn std::error::Error + 'static)) -> Option<bool> {
    use era::error::InputError;
    fn ask<E: InputError + 'static>(cause: &(dyn std::error::Error + 'static)) -> Option<bool> {
        cause.downcast_ref::<E>().map(E::is_input_error)
    }
    ask::<era::EraError>(cause)
        .or_else(|| ask::<era_io::IoError>(cause))
        .or_else(|| ask::<UsageError>(cause))
        .or_else(|| ask::<era::params::limits::LimitError>(cause))
        .or_else(|| ask::<era::friction::FrictionError>(cause))
        .or_else(|| ask::<era_plot::PlotError>(cause))
}

/// The error and its causes, `: `-joined as anyhow's `{:#}` does, with the core's
/// remedies naming flags ([`era::EraError::message`]), and a context such as
/// `reading FILE` followed by a cause that starts `FILE: ` names the file once:
/// `reading FILE: line 3: …`, not `reading FILE: FILE: line 3: …`.
fn message(err: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in err.chain() {
        // The core names options by their fields; the CLI's users know them as flags.
        let text = if let Some(e) = cause.downcast_ref::<era::EraError>() {
            e.message(era::params::Naming::Flag)
        } else if let Some(e) = cause.downcast_ref::<era::friction::FrictionError>() {
            e.message(era::params::Naming::Flag)
        } else if let Some(e) = cause.downcast_ref::<era::params::limits::LimitError>() {
            e.message(era::params::Naming::Flag)
        } else {
            cause.to_string()
        };
        let named = parts.last().and_then(|context| {
            let (_, subject) = context.split_once(' ')?;
            let rest = text.strip_prefix(subject)?.strip_prefix(": ")?;
            (!subject.is_empty()).then(|| rest.to_string())
        });
        parts.push(named.unwrap_or(text));
    }
    parts.join(": ")
}

/// Ends the process on SIGINT, SIGTERM or SIGHUP (exit 128 + the signal: 130, 143,
/// 129): era-io's clean-up first waits for a commit in progress, then removes this run's
/// temporary files, staging folders and folder locks, so earlier outputs stay whole and
/// nothing of the run is left. A thread waits for the signals; the work needs no check
/// points, and the exit comes within milliseconds. A second signal, should the clean-up
/// ever hang on the file system, ends the process at once (the signal's default). A
/// signal the process was started with ignored stays ignored (`nohup era …` ignores
/// SIGHUP; a background job of a script ignores SIGINT).
fn exit_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    use std::io::Write;
    let watched: Vec<i32> = [SIGINT, SIGTERM, SIGHUP]
        .into_iter()
        .filter(|&s| !ignored(s))
        .collect();
    let caught = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    for &signal in &watched {
        // Order matters: the default action is armed by the flag the first signal sets.
        let _ = signal_hook::flag::register_conditional_default(signal, caught.clone());
        let _ = signal_hook::flag::register(signal, caught.clone());
    }
    let Ok(mut signals) = signal_hook::iterator::Signals::new(&watched) else {
        return;
    };
    let _ = std::thread::Builder::new()
        .name("era-signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                era_io::atomic::abandon();
                let name = match signal {
                    SIGINT => "SIGINT",
                    SIGTERM => "SIGTERM",
                    _ => "SIGHUP",
                };
                // After a hang-up stderr may be gone: a failed write is no reason to stay.
                let _ = writeln!(
                    std::io::stderr(),
                    "era: stopped by {name}; outputs not yet in place were discarded, earlier ones are whole"
                );
                std::process::exit(128 + signal);
            }
        });
}

/// Whether `signal` is ignored (`SIG_IGN`), as the process was started.
fn ignored(signal: i32) -> bool {
    // SAFETY: sigaction with a null new action only reads the current one into `old`,
    // a zeroed sigaction owned here.
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        libc::sigaction(signal, std::ptr::null(), &mut old) == 0
            && old.sa_sigaction == libc::SIG_IGN
    }
}

fn main() -> ExitCode {
    output::report::mark_start();
    let cli = args::Cli::parse();
    exit_on_signals();
    std::panic::set_hook(Box::new(|info| {
        // A panic inside the MAT parser is turned into a file error by era-io.
        if !era_io::mat::containing_panic() {
            use std::io::Write;
            let _ = writeln!(std::io::stderr(), "era: internal error: {info}");
        }
    }));
    if matches!(cli.command, args::Command::Batch(_)) && cli.threads.is_some() {
        eprintln!(
            "era: error: --threads: era batch runs each record on one thread; give --jobs N for N records side by side"
        );
        return ExitCode::from(2);
    }
    let run = || match &cli.command {
        args::Command::Demo(a) => commands::demo::run(&a.into()),
        args::Command::Identify(a) => commands::identify::run(&config::Identify::new(a)?).map(drop),
        args::Command::Frf(a) => commands::frf::run(&a.into()),
        args::Command::Oma(a) => commands::oma::run(&config::Oma::new(a)?).map(drop),
        args::Command::Batch(a) => commands::batch::run(&a.into()),
        args::Command::Simulate(a) => commands::simulate::run(&a.into()),
        args::Command::Friction(a) => commands::friction::run(&a.into()),
        args::Command::Plot(a) => commands::plot::run(&a.into()),
        args::Command::Info(a) => commands::info::run(&a.into()),
        args::Command::Convert(a) => commands::convert::run(&a.into()),
        args::Command::Compare(a) => commands::compare::run(&a.as_ref().into()),
        args::Command::Refine(a) => commands::refine::run(&config::Refine::new(a)?),
        args::Command::Track(a) => commands::track::run(&config::Track::new(a)?),
    };
    // One thread setting for rayon and faer (era::parallel); a refused count is a usage
    // error like any flag's.
    let result = std::panic::catch_unwind(|| {
        era::parallel::with_threads(era::params::Naming::Flag, cli.threads, run)
            .map_err(anyhow::Error::from)
            .and_then(|r| r)
    });
    match result {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(err)) => {
            // Core errors spell the parameters they name as flags (EraError::message).
            eprintln!("era: error: {}", message(&err));
            ExitCode::from(exit_code(&err))
        }
        Err(_) => ExitCode::from(1),
    }
}

#[cfg(test)]
mod tests {
    use super::message;
    use anyhow::Context;

    #[test]
    fn a_file_named_by_the_context_and_its_error_is_named_once() {
        let io = std::io::Error::from(std::io::ErrorKind::NotFound);
        let err: anyhow::Result<()> = Err(anyhow::anyhow!("data/x.csv: {io}"));
        let err = err.context("reading data/x.csv").unwrap_err();
        let m = message(&err);
        assert_eq!(m, format!("reading data/x.csv: {io}"));
        // Other chains are joined as anyhow joins them.
        let err: anyhow::Result<()> = Err(anyhow::anyhow!("b.csv: bad"));
        let err = err.context("reading a.csv").unwrap_err();
        assert_eq!(message(&err), format!("{err:#}"));
    }
}
