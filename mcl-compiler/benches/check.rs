//! Parse + check (every semantic check, block verification included) of
//! generated programs of 10,000 and 100,000 lines, from scratch.
//! Run: `cargo bench -p mcl-compiler --bench check`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use mcl_compiler::{check_file, Database};
use std::path::Path;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("parse_and_check");
    g.sample_size(10);
    for lines in [10_000usize, 100_000] {
        let text = mcl_syntax::gen::program(lines, 7);
        g.throughput(Throughput::Elements(text.lines().count() as u64));
        g.bench_with_input(BenchmarkId::from_parameter(lines), &text, |b, text| {
            b.iter(|| {
                let mut db = Database::new();
                let f = db.set_text(Path::new("/virtual/gen.mcl"), text.as_str());
                let n = check_file(&db, f).len();
                assert_eq!(n, 0);
                n
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
