//! The command line: one clap `Parser`, one subcommand per headless job.

use clap::{Parser, Subcommand};

use crate::{app, bench, render, scenes, simulate};

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
    /// Time solvers: ms per frame, particle-steps per second, real-time factor.
    Bench(bench::Args),
}

impl Cli {
    /// Runs the chosen command.
    pub fn run(self) -> anyhow::Result<()> {
        match self.command {
            Some(Command::Tui(args)) => app::run(&args),
            Some(Command::Simulate(args)) => simulate::run(&args),
            Some(Command::Render(args)) => render::run(&args),
            Some(Command::Bench(args)) => bench::run(&args),
            Some(Command::Scenes) => {
                scenes::run();
                Ok(())
            }
            None => app::run(&app::Args::default()),
        }
    }
}
