//! `glint`: the command line. Every failure ends with one line on stderr
//! naming the file and the problem, a non-zero status, and no output file
//! left behind.

mod cli;
mod cmd;
mod cpu_check;
mod stats;

use std::process::ExitCode;

use clap::Parser;

use cli::{Cli, Command};
use cmd::one_line;

/// SIGINT and SIGTERM: remove unfinished outputs, say so in one line, exit
/// 130 / 143 (signal-hook's iterator runs the handler on a thread of its
/// own, where file removal and printing are safe).
fn install_signal_handlers() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    if let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) {
        std::thread::spawn(move || {
            if let Some(sig) = signals.forever().next() {
                let name = if sig == SIGINT { "SIGINT" } else { "SIGTERM" };
                cmd::outputs::on_signal(name, sig);
            }
        });
    }
}

fn main() -> ExitCode {
    if let Some(why) = cpu_check::refusal() {
        eprintln!("glint: {why}");
        return ExitCode::FAILURE;
    }
    install_panic_hook();
    install_signal_handlers();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => return parse_error(e),
    };
    // A panic unwinds through `Outputs::drop` (removing partial files), is
    // reported by the hook above, and ends here with status 101.
    // diff: 0 agree, 1 differ, 2 bad input (the contract).
    if let Command::Diff(args) = &cli.command {
        return match std::panic::catch_unwind(|| cmd::diff::run(args)) {
            Ok(Ok(true)) => ExitCode::SUCCESS,
            Ok(Ok(false)) => ExitCode::from(1),
            Ok(Err(e)) => {
                eprintln!("glint: {}", one_line(&format!("{e:#}")));
                ExitCode::from(2)
            }
            Err(_) => ExitCode::from(101),
        };
    }
    // test: 0 all agree, 1 any differs, 2 bad input (the contract).
    if let Command::Test(args) = &cli.command {
        return match std::panic::catch_unwind(|| cmd::test::run(args)) {
            Ok(Ok(code)) => ExitCode::from(code),
            Ok(Err(e)) => {
                eprintln!("glint: {}", one_line(&format!("{e:#}")));
                ExitCode::from(2)
            }
            Err(_) => ExitCode::from(101),
        };
    }
    // merge: every refusal is bad input, 2, as diff's.
    let all_bad_input = matches!(cli.command, Command::Merge(_));
    let result = match cli.command {
        Command::Render(args) => std::panic::catch_unwind(|| cmd::render::run(&args)),
        Command::Compare(args) => std::panic::catch_unwind(|| cmd::compare::run(&args)),
        Command::Bench(args) => std::panic::catch_unwind(|| cmd::bench::run(&args)),
        Command::Converge(args) => std::panic::catch_unwind(|| cmd::converge::run(&args)),
        Command::Info(args) => std::panic::catch_unwind(|| cmd::info::run(&args)),
        Command::Export(args) => std::panic::catch_unwind(|| cmd::export::run(&args)),
        Command::Stability(args) => std::panic::catch_unwind(|| cmd::stability::run(&args)),
        Command::Merge(args) => std::panic::catch_unwind(|| cmd::merge::run(&args)),
        Command::Diff(_) | Command::Test(_) => unreachable!("handled above"),
    };
    match result {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) => {
            eprintln!("glint: {}", one_line(&format!("{e:#}")));
            if all_bad_input || e.downcast_ref::<cmd::BadInput>().is_some() {
                ExitCode::from(2)
            } else {
                ExitCode::FAILURE
            }
        }
        Err(_) => ExitCode::from(101),
    }
}

/// A bug must still end in one line, not a backtrace: the last-resort
/// panic hook.
fn install_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        // Rust ignores SIGPIPE, so a closed stdout makes print! panic: end
        // as a filter does, not as a bug.
        if msg.starts_with("failed printing to stdout") && msg.contains("Broken pipe") {
            cmd::outputs::on_broken_pipe();
        }
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        eprintln!("glint: internal error: {}{at}", one_line(&msg));
    }));
}

/// clap's error as one line (help and version print and succeed; a
/// missing verb lists the verbs), exit 2.
fn parse_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
        let _ = e.print();
        return ExitCode::SUCCESS;
    }
    if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
        eprintln!(
            "glint: missing command: one of {} (see glint --help)",
            cli::VERBS.join(", ")
        );
        return ExitCode::from(2);
    }
    // clap's first paragraph is the error itself (a list of
    // missing arguments may follow its first line); then usage.
    let text = e.to_string();
    let first: Vec<&str> = text
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    eprintln!(
        "glint: {} (see glint --help)",
        first.join(" ").trim_start_matches("error: ")
    );
    ExitCode::from(2)
}
