//! Regenerates the optimisation tables 3.1-3.4 of Nøst (2023) on the thesis's riser scene
//! (docs/conventions.md: n = 10, l = 1 m, m = 1 kg, k = 1000 Nm/rad, k₁ = k₁₁ = 2000 Nm/rad, D = 0,
//! F = 2 N at node i, control at node 10, h = 0.01 s, N = 10), printing ours beside the thesis's.
//!
//! ```text
//! cargo run --release --example tables                 # all four tables, side by side
//! cargo run --release --example tables -- --table 3.2  # one table
//! cargo run --release --example tables -- --json       # machine-readable (docs/scene-format.md)
//! cargo run --release --example tables -- --help
//! ```
//!
//! How each table is solved and what each row is checked against: see `compute.rs` (shared
//! with `tests/scene/tables.rs`, which asserts every row).

mod compute;
mod thesis;

use compute::{Row, NAMES};
use std::time::Instant;

const USAGE: &str = "\
Regenerates Tables 3.1-3.4 of Nøst (2023) on the thesis's riser scene and prints them beside
the thesis's values.

usage: tables [--table 3.1|3.2|3.3|3.4] [--json] [--method auto|lbfgs|...]

options:
  --table T   only table T (3.1, 3.2, 3.3 or 3.4)
  --json      machine-readable output on stdout:
              {\"tables\": [{\"table\": \"3.1\", \"rows\": [{\"node\": 1, \"controls\": [...], ...}]}]}
  --method M  Table 3.4's method (default auto, the library's default, which takes the
              condensed solver there; lbfgs is the former default)
  -h, --help  this help
";

fn print_table(name: &str, rows: &[Row]) {
    println!("\nTable {name}");
    let per_step = rows.first().is_some_and(|r| r.controls.len() > 1);
    if per_step {
        println!(
            "{:>4} {:>13} {:>13} {:>9} {:>9} {:>8} {:>5} {:>7}  note",
            "node", "objective", "thesis", "|g|", "bound", "angle°", "iters", "ms"
        );
    } else {
        println!(
            "{:>4} {:>17} {:>17} {:>13} {:>13} {:>9} {:>5} {:>7}  note",
            "node", "u [N]", "thesis u [N]", "objective", "thesis", "|g|", "iters", "ms"
        );
    }
    for r in rows {
        if per_step {
            println!(
                "{:>4} {:>13.4e} {:>13.4e} {:>9.1e} {:>9} {:>8.2} {:>5} {:>7.2}  {}",
                r.node,
                r.objective,
                r.thesis_objective,
                r.gradient_norm,
                r.bound.map_or("-".into(), |b| format!("{b:.1}")),
                r.max_joint_angle_deg.unwrap_or(0.0),
                r.iterations,
                1e3 * r.seconds,
                r.note
            );
            if let Some(u) = &r.unbounded {
                println!(
                    "     unbounded from u = 0: c_sum = {:.4e}, max|u| = {:.1} N, angle {:.1}°  {}",
                    u.objective,
                    u.controls.iter().fold(0.0f64, |a, b| a.max(b.abs())),
                    u.max_joint_angle_deg.unwrap_or(f64::NAN),
                    u.note
                );
            }
        } else {
            println!(
                "{:>4} {:>17.8} {:>17.8} {:>13.4e} {:>13.4e} {:>9.1e} {:>5} {:>7.2}  {}",
                r.node,
                r.controls[0],
                r.thesis_controls[0],
                r.objective,
                r.thesis_objective,
                r.gradient_norm,
                r.iterations,
                1e3 * r.seconds,
                r.note
            );
        }
    }
    if per_step {
        println!("     controls u_0..u_10 [N] (ours / thesis):");
        for r in rows {
            let f = |v: &[f64]| {
                v.iter()
                    .map(|x| format!("{x:9.3}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            println!("{:>4} ours   {}", r.node, f(&r.controls));
            println!("{:>4} thesis {}", "", f(&r.thesis_controls));
        }
    }
    let total: f64 = rows.iter().map(|r| r.seconds).sum();
    println!("optimisation time for table {name}: {:.1} ms", 1e3 * total);
}

fn json_num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:e}")
    } else {
        "null".into()
    }
}

fn json_vec(v: &[f64]) -> String {
    format!(
        "[{}]",
        v.iter()
            .map(|x| json_num(*x))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

fn json_row(r: &Row, extra: bool) -> String {
    let mut s = format!(
        "{{\"node\": {}, \"controls\": {}, \"objective\": {}, \"thesis_controls\": {}, \
         \"thesis_objective\": {}, \"gradient_norm\": {}, \"seconds\": {}",
        r.node,
        json_vec(&r.controls),
        json_num(r.objective),
        json_vec(&r.thesis_controls),
        json_num(r.thesis_objective),
        json_num(r.gradient_norm),
        json_num(r.seconds)
    );
    if extra {
        s += &format!(
            ", \"bound\": {}, \"max_joint_angle_deg\": {}, \"folded\": {}",
            r.bound.map_or("null".into(), json_num),
            r.max_joint_angle_deg.map_or("null".into(), json_num),
            r.folded()
        );
        if let (Some(start), Some(objs)) = (r.start, r.start_objectives) {
            s += &format!(
                ", \"start\": \"{}\", \"start_objectives\": {}",
                start.label(),
                json_vec(&objs)
            );
        }
        if let Some(u) = &r.unbounded {
            s += &format!(", \"unbounded\": {}", json_row(u, true));
        }
    }
    s + "}"
}

/// The command line: `--table T`, `--json`, `--help`.
struct Args {
    json: bool,
    only: Option<String>,
    /// Table 3.4's method (`--method`, default auto).
    method: chainbeam::optimize::Method,
}

fn parse_args() -> std::result::Result<Option<Args>, String> {
    let mut args = Args {
        json: false,
        only: None,
        method: chainbeam::optimize::Method::Auto,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "-h" | "--help" => return Ok(None),
            "--json" => args.json = true,
            "--method" => {
                let m = it
                    .next()
                    .ok_or("--method needs a value, e.g. auto or lbfgs")?;
                args.method = m.parse().map_err(|e| format!("--method: {e}"))?;
            }
            "--table" => {
                let t = it
                    .next()
                    .ok_or("--table needs a value: 3.1, 3.2, 3.3 or 3.4")?;
                if !NAMES.contains(&t.as_str()) {
                    return Err(format!(
                        "unknown table {t}: expected one of 3.1, 3.2, 3.3, 3.4"
                    ));
                }
                args.only = Some(t);
            }
            _ => return Err(format!("unknown argument {a}")),
        }
    }
    Ok(Some(args))
}

fn run(args: &Args) -> Result<(), compute::TableError> {
    let mut out = Vec::new();
    let t0 = Instant::now();
    for name in NAMES {
        if args.only.as_deref().is_some_and(|o| o != name) {
            continue;
        }
        let rows = compute::table_with(name, args.method)?;
        if !args.json {
            print_table(name, &rows);
        }
        out.push((name, rows));
    }
    if args.json {
        let tables: Vec<String> = out
            .iter()
            .map(|(name, rows)| {
                let extra = *name == "3.3" || *name == "3.4";
                let rows: Vec<String> = rows.iter().map(|r| json_row(r, extra)).collect();
                format!("{{\"table\": \"{name}\", \"rows\": [{}]}}", rows.join(", "))
            })
            .collect();
        println!("{{\"tables\": [{}]}}", tables.join(", "));
    } else {
        println!(
            "\ntotal wall time {:.1} ms",
            1e3 * t0.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

fn main() {
    let args = match parse_args() {
        Ok(Some(a)) => a,
        Ok(None) => {
            print!("{USAGE}");
            return;
        }
        Err(e) => {
            eprintln!("error: {e}\nusage: tables [--table 3.1|3.2|3.3|3.4] [--json] (see --help)");
            std::process::exit(2);
        }
    };
    if let Err(e) = run(&args) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
