//! State-space exploration throughput on the large MCC nets.
//!
//! `cargo bench -p mcl-net --bench explore`; throughput is reported in states
//! ("elements") per second. The nets are read from `tests/data/mcc` (a copy of `shared/data/mcc`) in
//! the repository; the benchmark does nothing if that folder is absent.

use std::path::PathBuf;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use mcl_net::{analyze, read_pnml, Options};

const NETS: [&str; 3] = ["SharedMemory-PT-000010", "Kanban-PT-00005", "FMS-PT-00005"];

fn explore_large_nets(c: &mut Criterion) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/data/mcc");
    let mut group = c.benchmark_group("explore");
    group.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(20));
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
        let opts = Options::plain();
        let states = analyze(&net, &opts).states;
        group.throughput(Throughput::Elements(states));
        group.bench_function(name, |b| b.iter(|| std::hint::black_box(analyze(&net, &opts))));
    }
    group.finish();
}

criterion_group!(benches, explore_large_nets);
criterion_main!(benches);
