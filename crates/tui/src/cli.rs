//! The command line: one clap `Parser`, one subcommand per headless job, and the solver names
//! filled in from the registry.

use std::ffi::OsString;

use clap::builder::{PossibleValue, PossibleValuesParser};
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use cloth_solver::Registry;

use crate::{app, bench, render, scenes, simulate, solvers};

/// A CS184 mass-spring cloth simulator in the terminal.
#[derive(Debug, Parser)]
#[command(name = "clothsim", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The live terminal UI (the default): watch the cloth and edit it while it moves.
    Tui(app::Args),
    /// Run a scene headless and write the final state (JSON, or OBJ for a `.obj` file).
    Simulate(simulate::Args),
    /// Run a scene headless and print frames as text (plain, or ANSI colour).
    Render(render::Args),
    /// List the bundled scenes.
    Scenes,
    /// List the solvers of this build, with their options.
    Solvers,
    /// Time solvers: ms per frame, particle-steps per second, real-time factor.
    Bench(bench::Args),
}

impl Cli {
    /// Runs the chosen command with the solvers of `registry`.
    pub fn run(self, registry: &Registry) -> anyhow::Result<()> {
        match self.command {
            Some(Command::Tui(args)) => app::run(&args, registry),
            Some(Command::Simulate(args)) => simulate::run(&args, registry),
            Some(Command::Render(args)) => render::run(&args, registry),
            Some(Command::Bench(args)) => bench::run(&args, registry),
            Some(Command::Scenes) => scenes::run(),
            Some(Command::Solvers) => {
                let mut out = crate::output::Stdout::new();
                out.write_all_or_fail(solvers::listing(registry).as_bytes())?;
                out.finish()
            }
            None => app::run(&app::Args::default(), registry),
        }
    }
}

/// The command line of an application with `registry`'s solvers: every `--solver` accepts
/// exactly the registered names (listed with their descriptions in `--help`), and the top-level
/// help names them too.
pub fn command(registry: &Registry) -> clap::Command {
    let values: Vec<PossibleValue> = registry
        .entries()
        .iter()
        .map(|e| PossibleValue::new(e.name()).help(e.description()))
        .collect();
    let names = registry.names().collect::<Vec<_>>().join(", ");
    with_solver_values(Cli::command(), &values).after_help(format!(
        "Solvers: {names} (their options: `clothsim solvers`)."
    ))
}

/// Parses `args` (the program name first) against [`command`].
///
/// # Errors
/// clap's error (also for `--help` and `--version`, which print and succeed).
pub fn parse(registry: &Registry, args: Vec<OsString>) -> Result<Cli, clap::Error> {
    let matches = command(registry).try_get_matches_from(args)?;
    Cli::from_arg_matches(&matches)
}

/// `cmd` and its subcommands with the registered names as the values of every `--solver`.
fn with_solver_values(cmd: clap::Command, values: &[PossibleValue]) -> clap::Command {
    let ids: Vec<clap::Id> = cmd
        .get_arguments()
        .filter(|a| a.get_long() == Some("solver"))
        .map(|a| a.get_id().clone())
        .collect();
    let mut cmd = cmd;
    for id in ids {
        cmd = cmd.mut_arg(id, |a| {
            a.value_parser(PossibleValuesParser::new(values.iter().cloned()))
                .ignore_case(true)
        });
    }
    cmd.mut_subcommands(|sub| with_solver_values(sub, values))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn help(args: &[&str]) -> String {
        let mut cmd = command(&solvers::default_registry());
        let mut args = args.iter();
        let mut sub = &mut cmd;
        if let Some(first) = args.next() {
            sub = sub.find_subcommand_mut(first).unwrap();
        }
        sub.render_long_help().to_string()
    }

    #[test]
    fn every_help_with_a_solver_lists_the_registered_names() {
        let names: Vec<&str> = solvers::default_registry().names().collect();
        assert!(names.contains(&"verlet"));
        for page in [
            help(&[]),
            help(&["tui"]),
            help(&["simulate"]),
            help(&["render"]),
            help(&["bench"]),
        ] {
            for name in &names {
                assert!(page.contains(name), "{name} missing from:\n{page}");
            }
        }
    }

    #[test]
    fn a_solver_name_outside_the_registry_is_refused_by_the_parser() {
        let registry = solvers::default_registry();
        let args = ["clothsim", "simulate", "pinned4", "--solver", "rk4"].map(OsString::from);
        let e = parse(&registry, args.to_vec()).unwrap_err();
        assert_eq!(e.kind(), clap::error::ErrorKind::InvalidValue);
        assert!(e.to_string().contains("verlet"), "{e}");
        let args = ["clothsim", "simulate", "pinned4", "--solver", "VERLET"].map(OsString::from);
        assert!(parse(&registry, args.to_vec()).is_ok());
    }
}
