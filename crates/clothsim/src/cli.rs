//! The command line: one clap `Parser`, one subcommand per headless job, and the solver names
//! filled in from the registry.
//!
//! The live UI is the default command, and its flags work at the top level
//! (`clothsim sphere --paused`, `clothsim --fps 10`), as `hx FILE` and `btm --basic` do;
//! `clothsim tui ...` takes the same flags. A word that names a command is that command: a
//! scene file called `render` is opened as `clothsim ./render`, `clothsim tui render` or
//! `clothsim -- render`.

use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::str::FromStr;

use anyhow::Context as _;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{CommandFactory as _, FromArgMatches, Parser, Subcommand};
use clap_complete::Shell;
use cloth_render::{ColorChoice, Mode, View};
use cloth_solver::{OptionKind, Registry};

use crate::{bench, check, render, scenes, simulate};
use cloth_run::solvers;
use cloth_tui as app;
/// The name the program is known by in its help, version, completions and man page, when no
/// other is given: a plug-in binary (`clothsim-xpbd`) passes its own.
pub const PROGRAM: &str = "clothsim";

/// A few typical command lines, printed at the end of the top-level help, with [`PROGRAM`]
/// standing for the running program's name.
const EXAMPLES: &str = "\
Examples:
  clothsim                                  the live UI on the bundled pinned4 scene
  clothsim sphere --paused                  another bundled scene, paused
  clothsim my-scene.json --mode braille     a scene file, in braille dots
  clothsim render pinned4 --frames 200 --view all
  clothsim simulate sphere --set cloth.ks=20000 --out drape.obj
  clothsim simulate sphere --every 3 --out drape.pc2 --stats drape.csv
  clothsim render sphere --every 3 --format cast > sphere.cast
  clothsim compare pinned4 --vary cloth.ks=1,5000,100000
  clothsim bench --grid 50 --grid 128
  clothsim completions bash > ~/.local/share/bash-completion/completions/clothsim";

/// A CS184 mass-spring cloth simulator in the terminal.
///
/// With no command, opens the live terminal UI on SCENE (a bundled scene's name, see
/// `clothsim scenes`, or a scene JSON file; default pinned4).
#[derive(Debug, Parser)]
#[command(name = "clothsim", version, args_conflicts_with_subcommands = true)]
pub struct Cli {
    /// The live UI's arguments, when no command is given.
    #[command(flatten)]
    tui: crate::args::UiArgs,
    /// What to do.
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The live terminal UI (the default): watch the cloth and edit it while it moves.
    Tui(crate::args::UiArgs),
    /// The live UI on a parameter study: one pane per variant (`--vary KEY=V1,V2,...`),
    /// stepping together, with a table of their figures.
    Compare(crate::args::CompareArgs),
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
    /// Judge solvers by the conformance kit: every bundled scene's cases, each measure (energy,
    /// pins, stretch limit, settling, swaps) against its bound; exit 1 when a case fails.
    Check(check::Args),
    /// Print a shell completion script (commands, options, their values, bundled scenes).
    ///
    /// bash: `clothsim completions bash > ~/.local/share/bash-completion/completions/clothsim`;
    /// zsh: `clothsim completions zsh > ~/.zfunc/_clothsim` (with `~/.zfunc` in `fpath`);
    /// fish: `clothsim completions fish > ~/.config/fish/completions/clothsim.fish`.
    Completions {
        /// The shell to complete for.
        #[arg(value_enum)]
        shell: Shell,
    },
    /// Print the manual page (roff) to stdout, or write one page per command into a folder.
    ///
    /// Read it with `clothsim man | man -l -`.
    Man {
        /// Write clothsim.1 and one page per command (clothsim-render.1, ...) into this folder
        /// instead (made when missing).
        #[arg(long, value_name = "DIR", value_hint = clap::ValueHint::DirPath)]
        dir: Option<PathBuf>,
    },
}

impl Cli {
    /// Runs the chosen command with the solvers of `registry`; `program` is the name the
    /// completions and manual pages are written for.
    pub fn run(self, registry: &Registry, program: &str) -> anyhow::Result<()> {
        match self.command {
            Some(Command::Tui(args)) => app::run(&args.to_ui(), registry),
            Some(Command::Compare(args)) => app::run_compare(&args.to_ui(), registry),
            Some(Command::Simulate(args)) => simulate::run(&args, registry),
            Some(Command::Render(args)) => render::run(&args, registry),
            Some(Command::Bench(args)) => bench::run(&args, registry),
            Some(Command::Check(args)) => check::run(&args, registry),
            Some(Command::Scenes) => scenes::run(),
            Some(Command::Solvers) => print(solvers::listing(registry).as_bytes()),
            Some(Command::Completions { shell }) => print(&completions(registry, program, shell)),
            Some(Command::Man { dir: None }) => print(&man_page(registry, program)?),
            Some(Command::Man { dir: Some(dir) }) => {
                // The folder is made when missing: the pages are all that goes in it.
                std::fs::create_dir_all(&dir)
                    .with_context(|| format!("{}: cannot create the folder", dir.display()))?;
                clap_mangen::generate_to(command(registry, program), &dir)
                    .with_context(|| format!("{}: cannot write the manual pages", dir.display()))
            }
            None => app::run(&self.tui.to_ui(), registry),
        }
    }
}

/// The command line of an application with `registry`'s solvers, run as `program`: every
/// `--solver` accepts exactly the registered names (listed with their descriptions in
/// `--help`), the top-level help names them before its examples, and `--version` lists them.
///
/// `program` names the command in usage lines, `--version`, the manual pages and every help
/// text that shows a command line, so that a plug-in binary's help shows its own commands (its
/// solvers are not the `clothsim` binary's).
pub fn command(registry: &Registry, program: &str) -> clap::Command {
    let values: Vec<PossibleValue> = registry
        .entries()
        .iter()
        .map(|e| PossibleValue::new(e.name()).help(e.description()))
        .collect();
    let names = registry.names().collect::<Vec<_>>().join(", ");
    let orders: Vec<PossibleValue> = registry
        .entries()
        .iter()
        .filter_map(|e| e.option("order"))
        .flat_map(|o| match o.kind {
            OptionKind::Choice { choices, .. } => choices.to_vec(),
            _ => Vec::new(),
        })
        .fold(Vec::new(), |mut all: Vec<&str>, c| {
            if !all.contains(&c) {
                all.push(c);
            }
            all
        })
        .into_iter()
        .map(PossibleValue::new)
        .collect();
    // `--order` takes the `order` option's values of the registered solvers.
    let cmd = with_values(
        with_values(Cli::command(), "solver", &values),
        "order",
        &orders,
    )
    .after_help(format!(
        "Solvers: {names} (their options: `{PROGRAM} solvers`).\n\n{EXAMPLES}"
    ))
    .long_version(long_version(registry));
    named(cmd, program)
        .name(program.to_owned())
        .bin_name(program.to_owned())
}

/// `cmd` and its subcommands with every [`PROGRAM`] in their help texts (about, notes before
/// and after, and their arguments' help) replaced by `program`.
///
/// The help is written once, in doc comments, with `clothsim` for the program; every mention
/// is a command line or a file named after the command, so each becomes the running program.
fn named(cmd: clap::Command, program: &str) -> clap::Command {
    if program == PROGRAM {
        return cmd;
    }
    let swap = |text: &clap::builder::StyledStr| text.to_string().replace(PROGRAM, program);
    let mut cmd = cmd;
    if let Some(text) = cmd.get_about().map(swap) {
        cmd = cmd.about(text);
    }
    if let Some(text) = cmd.get_long_about().map(swap) {
        cmd = cmd.long_about(text);
    }
    if let Some(text) = cmd.get_before_help().map(swap) {
        cmd = cmd.before_help(text);
    }
    if let Some(text) = cmd.get_before_long_help().map(swap) {
        cmd = cmd.before_long_help(text);
    }
    if let Some(text) = cmd.get_after_help().map(swap) {
        cmd = cmd.after_help(text);
    }
    if let Some(text) = cmd.get_after_long_help().map(swap) {
        cmd = cmd.after_long_help(text);
    }
    let ids: Vec<clap::Id> = cmd.get_arguments().map(|a| a.get_id().clone()).collect();
    for id in ids {
        cmd = cmd.mut_arg(id, |arg| {
            let help = arg.get_help().map(swap);
            let long_help = arg.get_long_help().map(swap);
            let arg = match help {
                Some(text) => arg.help(text),
                None => arg,
            };
            match long_help {
                Some(text) => arg.long_help(text),
                None => arg,
            }
        });
    }
    cmd.mut_subcommands(|sub| named(sub, program))
}

/// Parses `args` (the program name first) against [`command`] for `program`.
///
/// # Errors
/// clap's error (also for `--help` and `--version`, which print and succeed).
pub fn parse(registry: &Registry, program: &str, args: Vec<OsString>) -> Result<Cli, clap::Error> {
    let matches = command(registry, program).try_get_matches_from(args)?;
    Cli::from_arg_matches(&matches)
}

/// `cmd` and its subcommands with `values` (the registered names, or their options' values) as
/// the values of every `--long`.
fn with_values(cmd: clap::Command, long: &str, values: &[PossibleValue]) -> clap::Command {
    let ids: Vec<clap::Id> = cmd
        .get_arguments()
        .filter(|a| a.get_long() == Some(long))
        .map(|a| a.get_id().clone())
        .collect();
    let mut cmd = cmd;
    for id in ids {
        cmd = cmd.mut_arg(id, |a| {
            a.value_parser(PossibleValuesParser::new(values.iter().cloned()))
                .ignore_case(true)
        });
    }
    cmd.mut_subcommands(|sub| with_values(sub, long, values))
}

/// Writes `bytes` to stdout through the one output path: a reader that went away (`| head`)
/// is a normal end, any other write error is an error.
fn print(bytes: &[u8]) -> anyhow::Result<()> {
    let mut out = cloth_run::output::Stdout::new();
    out.write_all_or_fail(bytes)?;
    out.finish()
}

/// The manual page of `program` (roff), its commands listed.
fn man_page(registry: &Registry, program: &str) -> anyhow::Result<Vec<u8>> {
    let mut page = Vec::new();
    clap_mangen::Man::new(command(registry, program))
        .render(&mut page)
        .context("cannot render the manual page")?;
    Ok(page)
}

/// The completion script of `program` for `shell`: it completes `program`, so the scripts of
/// clothsim and of a plug-in binary can be installed side by side.
///
/// clap_complete writes the commands, options and the values of enumerated options. A scene
/// argument takes a bundled name or a file, which a static script cannot know, so each shell
/// that allows it gets the bundled names (fixed when the binary was built, as the scenes are)
/// next to file names: bash through the words it offers at the scene's place, zsh through an
/// alternative of names and `*.json` files, fish through extra rules (fish merges them).
fn completions(registry: &Registry, program: &str, shell: Shell) -> Vec<u8> {
    let mut cmd = command(registry, program);
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut cmd, program, &mut script);
    // clap_complete's bash functions and case labels spell `-` as `__`; zsh's own function of
    // scene names takes the same shape, so two programs' functions never share a name.
    let label = program.replace('-', "__");
    let names: Vec<&str> = cloth_scene::BUNDLED.iter().map(|s| s.name).collect();
    let names = names.join(" ");
    let text = String::from_utf8_lossy(&script).into_owned();
    let text = match shell {
        // The bundled names join the word list of each command that takes a scene; the
        // `-o default` of the `complete` line falls back to file names when no word matches.
        Shell::Bash => {
            let labels: Vec<String> = std::iter::once((label.clone(), &cmd))
                .chain(
                    cmd.get_subcommands()
                        .map(|c| (format!("{label}__subcmd__{}", c.get_name()), c)),
                )
                .filter(|(_, c)| c.get_arguments().any(|a| a.get_id() == "scene"))
                .map(|(label, _)| format!("{label})"))
                .collect();
            // NOTE: for a program with a `-` in its name, clap_complete spells the case arms of
            // the subcommands (`a__subcmd__b__subcmd__render)`) otherwise than the states its
            // loop sets (`a__b__subcmd__render`), so no arm would ever match and nothing after
            // a command would complete; the arms are spelled here as the loop spells them.
            let misspelled = format!("{}__subcmd__", program.replace('-', "__subcmd__"));
            let spelled = format!("{label}__subcmd__");
            let mut out = String::with_capacity(text.len() + 512);
            let mut in_scene_command = false;
            for line in text.lines() {
                let arm = line.trim_start();
                let line = match arm.strip_prefix(misspelled.as_str()) {
                    Some(rest) if arm.ends_with(')') && !arm.contains([' ', ',']) => {
                        format!("{}{spelled}{rest}", &line[..line.len() - arm.len()])
                    }
                    _ => line.to_owned(),
                };
                let line = line.as_str();
                let trimmed = line.trim();
                if trimmed.ends_with(')') && !trimmed.contains(' ') {
                    in_scene_command = labels.iter().any(|l| l == trimmed);
                }
                match line.strip_suffix('"') {
                    Some(head) if in_scene_command && trimmed.starts_with("opts=\"") => {
                        out.push_str(head);
                        out.push(' ');
                        out.push_str(&names);
                        out.push('"');
                        in_scene_command = false;
                    }
                    _ => out.push_str(line),
                }
                out.push('\n');
            }
            out
        }
        Shell::Zsh => zsh_completions(&cmd, &text, program, &label, &names),
        Shell::Fish => {
            let mut text = text;
            let takes_scene = "__fish_seen_subcommand_from tui compare simulate render";
            let _ = write!(
                text,
                "\n# Bundled scenes and scene files where a scene is expected.\n\
                 complete -c {program} -n \"__fish_use_subcommand\" -a \"{names}\"\n\
                 complete -c {program} -n \"{takes_scene}\" -a \"{names}\"\n\
                 complete -c {program} -n \"{takes_scene}\" -k -a \"(__fish_complete_suffix .json)\"\n"
            );
            text
        }
        _ => text,
    };
    text.into_bytes()
}

/// clap_complete's zsh script `text` for `cmd` made right for a program whose first word is a
/// command or a scene (`clothsim render ...`, `clothsim sphere ...`), with the bundled `names`.
///
/// clap_complete gives the top level's optional scene the first place and the command the
/// second, so the first word was always taken for a scene: `clothsim render -<Tab>` offered
/// the live UI's flags and `clothsim simulate <Tab>` the commands again. Here the first place
/// offers both, and a first word that is no command is completed as `tui SCENE` is. Every
/// scene's action becomes a function offering the bundled names and `*.json` files.
fn zsh_completions(
    cmd: &clap::Command,
    text: &str,
    program: &str,
    label: &str,
    names: &str,
) -> String {
    let mut commands: Vec<&str> = cmd.get_subcommands().map(clap::Command::get_name).collect();
    if !commands.contains(&"help") {
        commands.push("help");
    }
    let commands = commands.join("|");
    let mut out = String::with_capacity(text.len() + 1024);
    // Until the top level's dispatch on its first word has been rewritten.
    let mut top = true;
    for (i, line) in text.lines().enumerate() {
        let is_scene = line.contains(":scene -- ") && line.ends_with(":_files' \\");
        if top && is_scene {
            // The top level's scene shares the first place with the commands.
            continue;
        }
        if top && line.starts_with("\":: :_") && line.ends_with("_commands\" \\") {
            let _ = writeln!(out, "\":: :_{label}_commands_or_scenes\" \\");
            continue;
        }
        if top && line.trim_start().starts_with("words=($line[2] ") {
            let indent = &line[..line.len() - line.trim_start().len()];
            let _ = writeln!(
                out,
                "{indent}case $line[1] in\n\
                 {indent}    ({commands}) ;;\n\
                 {indent}    (*)\n\
                 {indent}        # A scene: what follows is completed as after `tui SCENE`.\n\
                 {indent}        words=($line[1] \"${{words[@]}}\")\n\
                 {indent}        (( CURRENT += 1 ))\n\
                 {indent}        line[1]=tui\n\
                 {indent}        ;;\n\
                 {indent}esac"
            );
        }
        let line = if top && line.contains("$line[2]") {
            line.replace("$line[2]", "$line[1]")
        } else {
            line.to_owned()
        };
        if top && line.trim_start().starts_with("case $line[1] in") {
            top = false;
        }
        if is_scene {
            let cut = line.len() - ":_files' \\".len();
            out.push_str(&line[..cut]);
            let _ = write!(out, ":_{label}_scenes' \\");
        } else {
            out.push_str(&line);
        }
        out.push('\n');
        if i == 0 {
            let _ = write!(
                out,
                "\n_{label}_scenes() {{\n    \
                 _alternative 'scenes:bundled scene:({names})' \\\n        \
                 'files:scene file:_files -g \"*.json\"'\n}}\n\n\
                 _{label}_commands_or_scenes() {{\n    \
                 _alternative 'commands:command:_{program}_commands' \\\n        \
                 'scenes:bundled scene:({names})' \\\n        \
                 'files:scene file:_files -g \"*.json\"'\n}}\n"
            );
        }
    }
    out
}

/// `--version`'s text after the program's name: the version, the solvers of `registry` and the
/// vector paths.
fn long_version(registry: &Registry) -> String {
    let names: Vec<&str> = registry.names().collect();
    let missing = if cfg!(feature = "implicit") {
        ""
    } else {
        " (built without the `implicit` feature: no implicit solvers)"
    };
    format!(
        "{}\nsolvers: {}{missing}\nvector paths: {}",
        env!("CARGO_PKG_VERSION"),
        names.join(", "),
        cloth_solver::vector_paths()
    )
}

/// A parser that accepts exactly `values` (and their aliases, in any case, as the types'
/// own parsers do), lists them in `--help`, and converts with `T`'s `FromStr`.
fn choice<T>(values: impl IntoIterator<Item = PossibleValue>) -> impl TypedValueParser<Value = T>
where
    T: FromStr + Clone + Send + Sync + 'static,
    T::Err: std::error::Error + Send + Sync + 'static,
{
    PossibleValuesParser::new(values).try_map(|s| s.parse::<T>())
}

/// `--mode`: the glyph modes, from [`Mode::ALL`].
pub(crate) fn mode_parser() -> impl TypedValueParser<Value = Mode> {
    choice(Mode::ALL.map(|m| {
        PossibleValue::new(m.name()).help(match m {
            Mode::Ascii => "one pixel per cell, shaded by a glyph ramp",
            Mode::Half => "two pixels per cell in half blocks (shading needs colour)",
            Mode::Braille => "2 x 4 pixels per cell as braille dots",
        })
    }))
}

/// `--color`: when and how deep to colour.
pub(crate) fn color_parser() -> impl TypedValueParser<Value = ColorChoice> {
    choice([
        PossibleValue::new("auto").help(
            "interface colours on a terminal (NO_COLOR, CLICOLOR, CLICOLOR_FORCE respected); \
             the cloth in glyphs",
        ),
        PossibleValue::new("always").help("colour the cloth too, at the terminal's depth"),
        PossibleValue::new("never")
            .aliases(["none", "off"])
            .help("glyphs only"),
        PossibleValue::new("16")
            .alias("ansi16")
            .help("the 16 standard ANSI colours"),
        PossibleValue::new("256")
            .alias("ansi256")
            .help("the xterm 256-colour palette"),
        PossibleValue::new("truecolor")
            .alias("24bit")
            .help("24-bit colour"),
    ])
}

/// `render --view`: every view of [`View::ALL`], then `all`.
pub(crate) fn view_parser() -> impl TypedValueParser<Value = render::ViewArg> {
    choice(
        View::ALL
            .map(|v| {
                // `describe` starts with the view's name, which the list already shows.
                let axes = v
                    .describe()
                    .split_once(": ")
                    .map_or(v.describe(), |(_, a)| a);
                PossibleValue::new(v.name()).help(axes)
            })
            .into_iter()
            .chain([PossibleValue::new("all").help("side, top and front next to each other")]),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Cli {
        Cli::try_parse_from(std::iter::once("clothsim").chain(args.iter().copied()))
            .unwrap_or_else(|e| panic!("{args:?}: {e}"))
    }

    #[test]
    fn the_command_line_is_consistent() {
        command(&solvers::default_registry(), PROGRAM).debug_assert();
    }

    #[test]
    fn a_scene_and_ui_flags_at_the_top_level_open_the_ui() {
        let cli = parse(&["pinned2", "--paused"]);
        assert!(cli.command.is_none());
        assert_eq!(cli.tui.scene, "pinned2");
        assert!(cli.tui.paused);

        let cli = parse(&["--fps", "10"]);
        assert!(cli.command.is_none());
        assert_eq!(cli.tui.scene, "pinned4", "the default scene");
        assert_eq!(cli.tui.fps, 10);
        assert!(!cli.tui.paused);
    }

    #[test]
    fn the_tui_command_takes_the_same_flags() {
        let cli = parse(&[
            "tui", "sphere", "--paused", "--mode", "braille", "--fps", "5",
        ]);
        let Some(Command::Tui(args)) = cli.command else {
            panic!("tui parsed as {:?}", cli.command);
        };
        assert_eq!(args.scene, "sphere");
        assert!(args.paused);
        assert_eq!(args.mode, Mode::Braille);
        assert_eq!(args.fps, 5);
    }

    #[test]
    fn a_command_name_is_the_command_and_a_scene_file_of_that_name_stays_reachable() {
        assert!(matches!(
            parse(&["render", "pinned4"]).command,
            Some(Command::Render(_))
        ));
        for (args, scene) in [
            (&["./render"][..], "./render"),
            (&["--", "render"][..], "render"),
            (&["--paused", "--", "render"][..], "render"),
        ] {
            let cli = parse(args);
            assert!(cli.command.is_none(), "{args:?} opens the UI");
            assert_eq!(cli.tui.scene, scene, "{args:?}");
        }
        let Some(Command::Tui(args)) = parse(&["tui", "render"]).command else {
            panic!("tui render is the UI");
        };
        assert_eq!(args.scene, "render");
    }

    #[test]
    fn ui_flags_before_a_command_are_refused_rather_than_ignored() {
        let e = Cli::try_parse_from(["clothsim", "--paused", "simulate", "pinned4"])
            .expect_err("the UI's flag does not apply to simulate");
        assert_eq!(e.kind(), clap::error::ErrorKind::ArgumentConflict, "{e}");
    }

    #[test]
    fn enumerated_options_accept_their_listed_values_and_aliases_in_any_case() {
        let cli = parse(&["--mode", "HALF", "--color", "off"]);
        assert_eq!(cli.tui.mode, Mode::Half);
        assert_eq!(cli.tui.color, ColorChoice::Never);
        let cli = parse(&["--color", "24bit"]);
        assert_eq!(cli.tui.color, ColorChoice::TrueColor);
        let cli = parse(&["--color", "ALWAYS"]);
        assert_eq!(cli.tui.color, ColorChoice::Always);
        let e = Cli::try_parse_from(["clothsim", "--mode", "sixel"]).expect_err("not a mode");
        let e = e.to_string();
        assert!(e.contains("possible values: ascii, half, braille"), "{e}");
    }

    /// The long help of `clothsim COMMAND` (or the top level for `None`).
    fn long_help(command: Option<&str>) -> String {
        let mut cmd = super::command(&solvers::default_registry(), PROGRAM);
        let cmd = match command {
            Some(name) => cmd.find_subcommand_mut(name).expect("a command"),
            None => &mut cmd,
        };
        cmd.render_long_help().to_string()
    }

    #[test]
    fn every_enumerated_option_lists_its_values_in_help() {
        let top = long_help(None);
        for value in ["ascii", "half", "braille", "auto", "never", "truecolor"] {
            assert!(top.contains(&format!("- {value}:")), "{value} in:\n{top}");
        }
        let render = long_help(Some("render"));
        for value in [
            "side", "top", "bottom", "front", "orbit", "all", "plain", "ansi",
        ] {
            assert!(
                render.contains(&format!("- {value}:")),
                "{value} in:\n{render}"
            );
        }
        let bench = long_help(Some("bench"));
        for value in ["on", "off"] {
            assert!(
                bench.contains(&format!("- {value}:")),
                "{value} in:\n{bench}"
            );
        }
        // `--order` lists the registered solvers' `order` values (the help wraps: fold it).
        let folded = bench.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(
            folded.contains("[possible values: faithful, parallel, colored]"),
            "{bench}"
        );
        let completions = long_help(Some("completions"));
        for shell in ["bash", "zsh", "fish", "elvish", "powershell"] {
            assert!(completions.contains(shell), "{shell} in:\n{completions}");
        }
    }

    #[test]
    fn the_top_level_help_shows_the_ui_flags_the_commands_and_examples() {
        let top = long_help(None);
        for needle in [
            "--paused",
            "--fps",
            "[SCENE]",
            "render",
            "completions",
            "Examples:",
        ] {
            assert!(top.contains(needle), "{needle} in:\n{top}");
        }
        assert!(
            top.trim_end()
                .ends_with(EXAMPLES.lines().last().unwrap_or_default()),
            "the examples close the help:\n{top}"
        );
    }

    #[test]
    fn the_long_version_names_the_solvers_and_the_vector_paths() {
        let v = long_version(&solvers::default_registry());
        let v = v.as_str();
        assert!(v.starts_with(env!("CARGO_PKG_VERSION")), "{v}");
        assert!(v.contains("solvers: verlet"), "{v}");
        assert_eq!(
            v.contains("fast-implicit"),
            cfg!(feature = "implicit"),
            "the implicit solvers are listed exactly when built in: {v}"
        );
        assert!(v.contains("vector paths:"), "{v}");
        if cfg!(target_arch = "x86_64") {
            // Every x86-64 CPU has SSE2, so the baseline is always compiled in.
            assert!(v.contains("sse2"), "{v}");
            assert!(v.contains("avx2 ("), "{v}");
        }
    }

    #[test]
    fn completion_scripts_complete_commands_for_every_shell() {
        for shell in [
            Shell::Bash,
            Shell::Zsh,
            Shell::Fish,
            Shell::Elvish,
            Shell::PowerShell,
        ] {
            let text = String::from_utf8(completions(&solvers::default_registry(), PROGRAM, shell))
                .expect("UTF-8");
            for needle in ["simulate", "render", "frames", "mode"] {
                assert!(text.contains(needle), "{shell}: {needle} missing");
            }
            // Elvish and PowerShell scripts complete names only, not option values.
            if matches!(shell, Shell::Bash | Shell::Zsh | Shell::Fish) {
                assert!(text.contains("braille"), "{shell}: the values of --mode");
            }
        }
    }

    #[test]
    fn bash_zsh_and_fish_complete_the_bundled_scene_names() {
        for shell in [Shell::Bash, Shell::Zsh, Shell::Fish] {
            let text = String::from_utf8(completions(&solvers::default_registry(), PROGRAM, shell))
                .expect("UTF-8");
            for scene in cloth_scene::BUNDLED {
                assert!(
                    text.contains(scene.name),
                    "{shell}: scene {} missing",
                    scene.name
                );
            }
        }
        let bash = String::from_utf8(completions(
            &solvers::default_registry(),
            PROGRAM,
            Shell::Bash,
        ))
        .expect("UTF-8");
        let with_scenes = bash
            .lines()
            .filter(|l| l.trim().starts_with("opts=") && l.contains(" pinned4 "))
            .count();
        assert_eq!(
            with_scenes, 5,
            "top level, tui, compare, simulate and render:\n{bash}"
        );
        let zsh = String::from_utf8(completions(
            &solvers::default_registry(),
            PROGRAM,
            Shell::Zsh,
        ))
        .expect("UTF-8");
        assert!(zsh.contains("_files -g"), "zsh offers scene files too");
        assert_eq!(
            zsh.matches(":_clothsim_scenes'").count(),
            4,
            "the scene of tui, compare, simulate and render:\n{zsh}"
        );
        assert!(
            zsh.contains("\":: :_clothsim_commands_or_scenes\""),
            "the top level's first word, a command or a scene:\n{zsh}"
        );
    }

    /// Whether `text` names `clothsim` anywhere other than as part of `clothsim-xpbd`.
    fn names_clothsim_alone(text: &str) -> bool {
        text.replace("clothsim-xpbd", "").contains("clothsim")
    }

    #[test]
    fn a_plug_in_binary_is_named_by_its_own_name_everywhere() {
        let registry = solvers::default_registry();
        let program = "clothsim-xpbd";
        let mut cmd = command(&registry, program);
        assert!(
            cmd.render_version().starts_with("clothsim-xpbd 0."),
            "{}",
            cmd.render_version()
        );
        let help = cmd.render_long_help().to_string();
        assert!(help.contains("clothsim-xpbd sphere --paused"), "{help}");
        assert!(help.contains("`clothsim-xpbd scenes`"), "{help}");
        assert!(!names_clothsim_alone(&help), "{help}");
        for sub in ["simulate", "render", "bench", "completions", "man"] {
            let page = cmd
                .find_subcommand_mut(sub)
                .map(|c| c.render_long_help().to_string())
                .unwrap_or_default();
            assert!(!names_clothsim_alone(&page), "{sub}:\n{page}");
        }

        let bash = String::from_utf8(completions(&registry, program, Shell::Bash)).expect("UTF-8");
        assert!(
            bash.contains(
                "complete -F _clothsim__xpbd -o nosort -o bashdefault -o default clothsim-xpbd"
            ),
            "{bash}"
        );
        assert!(
            !names_clothsim_alone(&bash.replace("clothsim__xpbd", "")),
            "{bash}"
        );
        let with_scenes = bash
            .lines()
            .filter(|l| l.trim().starts_with("opts=") && l.contains(" pinned4 "))
            .count();
        assert_eq!(with_scenes, 5, "the scene names are still offered:\n{bash}");
        let zsh = String::from_utf8(completions(&registry, program, Shell::Zsh)).expect("UTF-8");
        assert!(zsh.starts_with("#compdef clothsim-xpbd"), "{zsh}");
        assert_eq!(zsh.matches(":_clothsim__xpbd_scenes'").count(), 4, "{zsh}");
        assert!(
            zsh.contains("_alternative 'commands:command:_clothsim-xpbd_commands'"),
            "{zsh}"
        );
        assert!(zsh.contains("\n_clothsim__xpbd_scenes() {"), "{zsh}");
        let fish = String::from_utf8(completions(&registry, program, Shell::Fish)).expect("UTF-8");
        assert!(fish.contains("complete -c clothsim-xpbd -n"), "{fish}");
        assert!(!fish.contains("complete -c clothsim "), "{fish}");

        let page =
            String::from_utf8(man_page(&registry, program).expect("renders")).expect("UTF-8");
        assert!(page.contains(".TH clothsim-xpbd 1"), "{page}");
        assert!(page.contains("`clothsim\\-xpbd scenes`"), "{page}");
    }

    #[test]
    fn the_man_page_is_roff_and_lists_the_commands() {
        let page =
            String::from_utf8(man_page(&solvers::default_registry(), PROGRAM).expect("renders"))
                .expect("UTF-8");
        assert!(
            page.starts_with(".ie") || page.contains(".TH clothsim 1"),
            "{page}"
        );
        for needle in ["simulate", "render", "completions", "\\-\\-paused"] {
            assert!(page.contains(needle), "{needle} in:\n{page}");
        }
    }

    fn help(args: &[&str]) -> String {
        let mut cmd = command(&solvers::default_registry(), PROGRAM);
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
        let e = super::parse(&registry, PROGRAM, args.to_vec()).unwrap_err();
        assert_eq!(e.kind(), clap::error::ErrorKind::InvalidValue);
        assert!(e.to_string().contains("verlet"), "{e}");
        let args = ["clothsim", "simulate", "pinned4", "--solver", "VERLET"].map(OsString::from);
        assert!(super::parse(&registry, PROGRAM, args.to_vec()).is_ok());
    }
}
