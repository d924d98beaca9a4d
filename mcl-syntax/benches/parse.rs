//! Parsing speed on generated programs (`mcl_syntax::gen::program`) of
//! 1,000, 10,000 and 100,000 lines: `cargo bench -p mcl-syntax --bench parse`.
//! Throughput is reported in bytes; lines/s = lines / time.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use std::hint::black_box;
use std::time::Duration;

fn parse(c: &mut Criterion) {
    let mut group = c.benchmark_group("parse");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    for lines in [1_000usize, 10_000, 100_000] {
        let src = mcl_syntax::gen::program(lines, 42);
        let n = src.lines().count();
        assert!(mcl_syntax::parse(&src).errors.is_empty());
        group.throughput(Throughput::Bytes(src.len() as u64));
        group.bench_with_input(BenchmarkId::new("lines", n), &src, |b, src| {
            b.iter(|| mcl_syntax::parse(black_box(src)))
        });
    }
    group.finish();

    // The lexer alone, to see how the time splits.
    let mut group = c.benchmark_group("lex");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2));
    let src = mcl_syntax::gen::program(10_000, 42);
    group.throughput(Throughput::Bytes(src.len() as u64));
    group.bench_with_input(BenchmarkId::new("lines", src.lines().count()), &src, |b, src| {
        b.iter(|| mcl_syntax::lexer::lex(black_box(src)))
    });
    group.finish();
}

criterion_group!(benches, parse);
criterion_main!(benches);
