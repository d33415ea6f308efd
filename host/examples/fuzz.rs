//! The stable fuzz driver: `cargo run --release -p host --features fuzz --example fuzz -- TARGET|all [N] [SEED]`
//! runs N (default 10⁶) seeded mutations of each target's corpus through the same `fuzz_one` the
//! cargo-fuzz targets in `fuzz/` call, and prints the counts. Peak memory:
//! `/usr/bin/time -v target/release/examples/fuzz all 1000000` ("Maximum resident set size").

use host::fuzz::{drive, Target};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let which = args.first().map_or("all", String::as_str);
    let n: u64 = args
        .get(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let targets: Vec<Target> = if which == "all" {
        Target::ALL.to_vec()
    } else if let Some(t) = Target::from_name(which) {
        vec![t]
    } else {
        eprintln!(
            "error: unknown target '{which}'; one of all, {}",
            Target::ALL.map(Target::name).join(", ")
        );
        std::process::exit(2);
    };
    for t in targets {
        let started = Instant::now();
        let c = drive(t, n, seed);
        println!(
            "{:<12} {} inputs ({} mutated corpus entries, {} random), seed {seed}, no panic, {:.1} s",
            t.name(),
            c.inputs,
            c.mutated,
            c.inputs - c.mutated,
            started.elapsed().as_secs_f64()
        );
    }
}
