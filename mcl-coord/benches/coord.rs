//! Supervisor synthesis and deadlock analysis for 2, 4 and 8 vehicles with
//! 10 to 50 constraints (numbers in BENCHMARKS.md, section mcl-coord).
//!
//! Each vehicle runs a sequence of steps; step k is `parallel { A : sK_a }
//! and { B : sK_b }` over tasks of examples/vehicle.mcl. Constraints are
//! drawn at random between labelled calls of different vehicles: orders go
//! from an earlier step to a later one, syncs join calls of the same step,
//! mutexes any two calls (β = 1).
//!
//! `teams`: the same vehicles in pairs (8 vehicles = 4 teams), every
//! constraint a mutex between the two vehicles of one team (free of
//! deadlock; the analysis verifies each team apart).

use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use mcl_compiler::{Database, Db};
use mcl_coord::{analyze_with, centralize, AnalyzeOptions, Constraint, Mission};

const STEPS: usize = 3;
const TASKS: &[&str] = &["Surface()", "GotoTarget()", "Deploy()", "Goto( p )", "SendData()", "TakeImages()"];

struct Rng(u64);
impl Rng {
    fn below(&mut self, n: usize) -> usize {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 33) % n as u64) as usize
    }
}

pub fn program(vehicles: usize, constraints: usize, seed: u64) -> String {
    let mut r = Rng(seed);
    let mut text = String::from("import \"vehicle.mcl\";\n");
    for v in 0..vehicles {
        let steps: Vec<String> = (0..STEPS)
            .map(|k| {
                format!(
                    "parallel {{ {} : s{k}_a }} and {{ {} : s{k}_b }}",
                    TASKS[r.below(TASKS.len())],
                    TASKS[r.below(TASKS.len())]
                )
            })
            .collect();
        text.push_str(&format!("mission : v{v} {{ {} }}\n", steps.join(" ; ")));
    }
    text.push_str("constraints {\n");
    for _ in 0..constraints {
        let (a, mut b) = (r.below(vehicles), r.below(vehicles));
        if a == b {
            b = (b + 1) % vehicles;
        }
        let side = |r: &mut Rng| if r.below(2) == 0 { "a" } else { "b" };
        match r.below(3) {
            0 => {
                let k = r.below(STEPS - 1);
                let l = k + 1 + r.below(STEPS - 1 - k);
                text.push_str(&format!("  order {{ v{a}:s{k}_{}, v{b}:s{l}_{} }}\n", side(&mut r), side(&mut r)));
            }
            1 => {
                let k = r.below(STEPS);
                text.push_str(&format!("  sync {{ v{a}:s{k}_{}, v{b}:s{k}_{} }}\n", side(&mut r), side(&mut r)));
            }
            _ => {
                let (k, l) = (r.below(STEPS), r.below(STEPS));
                text.push_str(&format!("  mutex {{ v{a}:s{k}_{}, v{b}:s{l}_{} }} = 1\n", side(&mut r), side(&mut r)));
            }
        }
    }
    text.push_str("}\n");
    text
}

/// Vehicles in pairs; `constraints` mutexes, each within one pair.
pub fn teams_program(vehicles: usize, constraints: usize, seed: u64) -> String {
    let mut r = Rng(seed);
    let text = program(vehicles, 0, seed);
    let mut text = text.trim_end().trim_end_matches('}').trim_end().trim_end_matches("constraints {").to_string();
    text.push_str("constraints {\n");
    for _ in 0..constraints {
        let team = r.below(vehicles / 2);
        let (a, b) = (2 * team, 2 * team + 1);
        let side = |r: &mut Rng| if r.below(2) == 0 { "a" } else { "b" };
        let (k, l) = (r.below(STEPS), r.below(STEPS));
        text.push_str(&format!("  mutex {{ v{a}:s{k}_{}, v{b}:s{l}_{} }} = 1\n", side(&mut r), side(&mut r)));
    }
    text.push_str("}\n");
    text
}

pub fn load(vehicles: usize, constraints: usize) -> (Vec<Mission>, Vec<Constraint>) {
    load_text(vehicles, constraints, &program(vehicles, constraints, 7 + vehicles as u64 * 100 + constraints as u64))
}

pub fn load_text(vehicles: usize, constraints: usize, text: &str) -> (Vec<Mission>, Vec<Constraint>) {
    let dir = std::env::temp_dir().join(format!("mcl-coord-bench-{vehicles}-{constraints}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let vehicle = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/vehicle.mcl");
    std::fs::copy(vehicle, dir.join("vehicle.mcl")).unwrap();
    let path = dir.join("m.mcl");
    std::fs::write(&path, text).unwrap();
    let db = Database::new();
    let file = db.file(&path);
    let out = mcl_coord::source::load(&db, file).expect("benchmark program compiles");
    let _ = std::fs::remove_dir_all(&dir);
    out
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("coord");
    g.sample_size(10);
    let random = [(2, 10), (2, 50), (4, 10), (4, 50), (8, 10), (8, 30), (8, 50)];
    let teams = [(8, 10), (8, 50)];
    let cases = random.iter().map(|&(v, k)| ("", v, k)).chain(teams.iter().map(|&(v, k)| ("teams-", v, k)));
    for (family, v, k) in cases {
        let (ms, cs) =
            if family.is_empty() { load(v, k) } else { load_text(v, k, &teams_program(v, k, 11 + k as u64)) };
        g.bench_with_input(BenchmarkId::new("synthesis", format!("{family}{v}v-{k}c")), &(), |b, _| {
            b.iter(|| {
                let plant = centralize(&ms).unwrap();
                mcl_coord::supervisor::synthesize(&plant, &cs).unwrap()
            })
        });
        let opts = AnalyzeOptions::default();
        let r = analyze_with(&ms, &cs, &opts).unwrap();
        eprintln!(
            "{family}{v} vehicles, {k} constraints: {:?}, {} supervisors ({} added), vehicle classes {:?}, product {} states",
            r.verdict,
            r.supervisors.len(),
            r.added,
            r.stats.vehicle_classes,
            r.stats.product_states
        );
        g.bench_with_input(BenchmarkId::new("analysis", format!("{family}{v}v-{k}c")), &(), |b, _| {
            b.iter(|| analyze_with(&ms, &cs, &opts).unwrap())
        });
        // What `mcl check` runs: the same without the structural report
        // (invariants and siphons of the final net).
        let check = AnalyzeOptions { structure: false, ..AnalyzeOptions::default() };
        g.bench_with_input(BenchmarkId::new("check", format!("{family}{v}v-{k}c")), &(), |b, _| {
            b.iter(|| analyze_with(&ms, &cs, &check).unwrap())
        });
        let sups = r.supervisors.clone();
        g.bench_with_input(BenchmarkId::new("decentralize", format!("{family}{v}v-{k}c")), &(), |b, _| {
            b.iter(|| mcl_coord::decentralize(&ms, &sups).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
