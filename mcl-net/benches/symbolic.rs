//! Decision-diagram exploration (`--method symbolic`) on the large MCC nets.
//!
//! `cargo bench -p mcl-net --bench symbolic`; throughput is reported in
//! reachable markings ("elements") per second. The nets are read from
//! `tests/data/mcc`; the benchmark does nothing if that folder is absent.

use std::path::PathBuf;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mcl_net::explore::{explore_symbolic, SymbolicOptions};
use mcl_net::read_pnml;

const NETS: [&str; 3] = ["SharedMemory-PT-000010", "Kanban-PT-00005", "FMS-PT-00005"];

fn symbolic_large_nets(c: &mut Criterion) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/data/mcc");
    let mut group = c.benchmark_group("symbolic");
    group.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(10));
    let opts = SymbolicOptions::default();
    for name in NETS {
        let Ok(text) = std::fs::read_to_string(dir.join(format!("{name}.pnml"))) else {
            eprintln!("note: {name} not found in {}; skipped", dir.display());
            continue;
        };
        let net = match read_pnml(&text) {
            Ok(n) => n,
            Err(e) => {
                eprintln!("{name}: {e}");
                continue;
            }
        };
        let states = explore_symbolic(&net, &opts).states.unwrap_or(0);
        group.throughput(Throughput::Elements(u64::try_from(states).unwrap_or(u64::MAX)));
        group.bench_function(name, |b| b.iter(|| std::hint::black_box(explore_symbolic(&net, &opts))));
    }
    group.finish();
}

criterion_group!(benches, symbolic_large_nets);
criterion_main!(benches);
