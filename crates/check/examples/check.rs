//! Runs the kit on one of the workspace's solvers and prints its report:
//! `cargo run -p cloth-check --release --example check -- fast-implicit [--full] [--json]
//! [--scene NAME]... [--threads N] [--ks-scale X]`.

use std::process::ExitCode;

use cloth_check::CheckOptions;
use cloth_implicit::{FastImplicit, ImplicitEuler};
use cloth_solver::Verlet;

fn main() -> ExitCode {
    let mut args = std::env::args().skip(1);
    let mut name = None;
    let mut json = false;
    let mut options = CheckOptions::default();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--full" => options.full = true,
            "--json" => json = true,
            "--scene" => options.scenes.extend(args.next()),
            "--threads" => options.threads = args.next().and_then(|t| t.parse().ok()).unwrap_or(1),
            "--ks-scale" => {
                options.ks_scale = args.next().and_then(|t| t.parse().ok()).unwrap_or(1.0);
            }
            other => name = Some(other.to_owned()),
        }
    }
    let entry = match name.as_deref().unwrap_or("verlet") {
        "verlet" => Verlet::ENTRY,
        "implicit" => ImplicitEuler::ENTRY,
        "fast-implicit" => FastImplicit::ENTRY,
        other => {
            eprintln!("unknown solver {other:?}: verlet, implicit or fast-implicit");
            return ExitCode::from(2);
        }
    };
    let report = cloth_check::check_each(&entry, &serde_json::json!({}), &options, &mut |c| {
        eprintln!("{c}");
    });
    match report {
        Ok(report) => {
            if json {
                match serde_json::to_string_pretty(&report) {
                    Ok(text) => println!("{text}"),
                    Err(e) => eprintln!("{e}"),
                }
            } else {
                println!("{report}");
                if let Ok(text) = serde_json::to_string_pretty(&report.to_expected()) {
                    eprintln!("failures as list entries:\n{text}");
                }
            }
            if report.passed() {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            }
        }
        Err(e) => {
            eprintln!("{e}");
            ExitCode::from(2)
        }
    }
}
