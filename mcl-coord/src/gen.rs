//! Generated fleets for the coordination analysis at scale (issue 17):
//! `vehicles` missions of 10 to 20 calls each and 20 to 60 constraints
//! (mutex, order, sync) that link every vehicle, deterministic by seed.
//!
//! Every call runs inside `try { ... } catch { Void() }`, so that a failure
//! never skips the calls after it (a skipped call would leave its order or
//! sync partners waiting: E0406 for almost any constraint). The calls of
//! each mission sit in *slots* (call `i` of every mission in slot `i`):
//! orders go from an earlier slot to a later one, syncs join calls of the
//! same slot, mutexes join any two calls (a fifth of the constraints
//! mutexes, half orders, the rest syncs). Such a fleet is free of
//! deadlock: a mutex is taken atomically with everything else a call
//! waits for and given back when the call ends, and the waiting call of
//! the lowest slot waits only for calls of lower slots, which do not wait
//! (`tests/fleet.rs` confirms it with the verifier's product at 4 and 8
//! vehicles, and with every dead marking of the centralised supervised net
//! up to 16).
//! A fleet generated with `deadlock` adds a *backward* order, a cycle
//! through two missions' sequences: vehicle `x` waits at an early call for
//! a late call of `y`, which waits at an earlier call for a later call of
//! `x`.
//!
//! The text imports `vehicle.mcl` (`examples/vehicle.mcl`).

use std::fmt::Write;

/// What to generate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FleetSpec {
    /// Number of missions (at least 2).
    pub vehicles: usize,
    /// The seed of every random choice.
    pub seed: u64,
    /// Add a cycle of orders that deadlocks.
    pub deadlock: bool,
}

/// A generated fleet.
#[derive(Clone, Debug)]
pub struct Fleet {
    /// The MCL text (imports `vehicle.mcl`).
    pub text: String,
    /// Calls of each mission.
    pub calls: Vec<usize>,
    /// Number of constraints.
    pub constraints: usize,
}

/// Tasks without parameters of `examples/vehicle.mcl`.
const TASKS: &[&str] = &["Surface", "GotoTarget", "Deploy", "SendData", "ReceiveData", "TakeImages", "GetPositionFix"];

/// SplitMix64: small, deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `lo..=hi`.
    fn range(&mut self, lo: usize, hi: usize) -> usize {
        lo + (self.next() % (hi - lo + 1) as u64) as usize
    }
}

/// The number of constraints of a fleet of `n` vehicles: 20 to 60, more
/// with more vehicles.
fn constraint_count(n: usize, rng: &mut Rng) -> usize {
    let lo = (3 * n).clamp(20, 50);
    let hi = (4 * n).clamp(24, 60);
    rng.range(lo, hi)
}

/// Generates the fleet of `spec` (fewer than 2 vehicles count as 2).
pub fn fleet(spec: &FleetSpec) -> Fleet {
    let n = spec.vehicles.max(2);
    let mut rng = Rng(spec.seed ^ (n as u64) << 32 ^ u64::from(spec.deadlock) << 48);
    let calls: Vec<usize> = (0..n).map(|_| rng.range(10, 20)).collect();
    let total = constraint_count(n, &mut rng);
    let mut labelled: Vec<Vec<bool>> = calls.iter().map(|&k| vec![false; k]).collect();
    let mut cs: Vec<String> = Vec::new();
    // Pairs of calls in one sync or one mutex: a mutex of two calls of one
    // sync would contradict it (E0408).
    let mut synced: Vec<((usize, usize), (usize, usize))> = Vec::new();
    let mut mutexed: Vec<((usize, usize), (usize, usize))> = Vec::new();
    let label = |labelled: &mut Vec<Vec<bool>>, v: usize, i: usize| {
        labelled[v][i] = true;
        format!("v{v}:c{i}")
    };
    let mut k = 0usize;
    while cs.len() < total {
        // The first n - 1 constraints chain the vehicles; then at random.
        let (x, y) = if k < n - 1 {
            (k, k + 1)
        } else {
            let x = rng.range(0, n - 1);
            let mut y = rng.range(0, n - 2);
            if y >= x {
                y += 1;
            }
            (x, y)
        };
        let kind = rng.range(0, 9);
        let top = calls[x].min(calls[y]);
        if kind < 2 {
            let (i, j) = (rng.range(0, calls[x] - 1), rng.range(0, calls[y] - 1));
            let p = ((x, i), (y, j));
            if synced.iter().any(|&(a, b)| (a, b) == p || (b, a) == p) {
                continue;
            }
            mutexed.push(p);
            let (a, b) = (label(&mut labelled, x, i), label(&mut labelled, y, j));
            cs.push(format!("mutex {{ {a}, {b} }} = 1"));
            k += 1;
        } else if kind < 7 {
            // From an earlier slot to a later one.
            let i = rng.range(0, top - 2);
            let j = rng.range(i + 1, calls[y] - 1);
            let (a, b) = (label(&mut labelled, x, i), label(&mut labelled, y, j));
            cs.push(format!("order {{ {a}, {b} }}"));
            k += 1;
        } else {
            let i = rng.range(0, top - 1);
            let p = ((x, i), (y, i));
            if mutexed.iter().any(|&(a, b)| (a, b) == p || (b, a) == p) {
                continue;
            }
            synced.push(p);
            let (a, b) = (label(&mut labelled, x, i), label(&mut labelled, y, i));
            cs.push(format!("sync {{ {a}, {b} }}"));
            k += 1;
        }
    }
    if spec.deadlock {
        // x waits at call i for y's call j2 (> j); y waits at call j for
        // x's call i2 (> i): neither reaches the call the other waits for.
        let x = rng.range(0, n - 1);
        let y = (x + 1 + rng.range(0, n - 2)) % n;
        let i = rng.range(0, calls[x] - 2);
        let i2 = rng.range(i + 1, calls[x] - 1);
        let j = rng.range(0, calls[y] - 2);
        let j2 = rng.range(j + 1, calls[y] - 1);
        let (a, b) = (label(&mut labelled, x, i2), label(&mut labelled, y, j));
        cs.push(format!("order {{ {a}, {b} }}"));
        let (a, b) = (label(&mut labelled, y, j2), label(&mut labelled, x, i));
        cs.push(format!("order {{ {a}, {b} }}"));
    }
    let mut text = String::from("import \"vehicle.mcl\";\n\n");
    let _ = writeln!(
        text,
        "// Generated by mcl_coord::gen::fleet: {n} vehicles, seed {}, {} constraints{}.",
        spec.seed,
        cs.len(),
        if spec.deadlock { ", with a cycle of orders" } else { "" }
    );
    for (v, &k) in calls.iter().enumerate() {
        let _ = writeln!(text, "mission : v{v} {{");
        for (i, &lab) in labelled[v].iter().enumerate() {
            let task = TASKS[rng.range(0, TASKS.len() - 1)];
            let l = if lab { format!(" : c{i}") } else { String::new() };
            let sep = if i + 1 < k { " ;" } else { "" };
            let _ = writeln!(text, "    try {{ {task}(){l} }} catch {{ Void() }}{sep}");
        }
        let _ = writeln!(text, "}}");
    }
    let _ = writeln!(text, "\nconstraints {{");
    for c in &cs {
        let _ = writeln!(text, "    {c}");
    }
    let _ = writeln!(text, "}}");
    Fleet { text, calls, constraints: cs.len() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fleets_are_deterministic_and_within_the_bounds() {
        for n in [4, 8, 12, 16] {
            for deadlock in [false, true] {
                let spec = FleetSpec { vehicles: n, seed: 7, deadlock };
                let f = fleet(&spec);
                assert_eq!(f.text, fleet(&spec).text);
                assert_eq!(f.calls.len(), n);
                assert!(f.calls.iter().all(|&k| (10..=20).contains(&k)), "{:?}", f.calls);
                assert!((20..=62).contains(&f.constraints), "{n}: {}", f.constraints);
                assert_eq!(f.text.matches("mission : ").count(), n);
            }
        }
        assert_ne!(
            fleet(&FleetSpec { vehicles: 8, seed: 1, deadlock: false }).text,
            fleet(&FleetSpec { vehicles: 8, seed: 2, deadlock: false }).text
        );
    }
}
