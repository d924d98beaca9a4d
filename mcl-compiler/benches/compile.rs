//! Compile time (check + composition into one net) for missions of 1,000,
//! 10,000 and 100,000 task calls. Run: `cargo bench -p mcl-compiler --bench compile`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use mcl_compiler::compile::compile_file;
use mcl_compiler::Database;
use std::path::Path;

const VEHICLE: &str = r#"
actions {
    enableGoto = GotoPrimitive( c: enable, v: way-point ); disableGoto = GotoPrimitive( c: disable );
    enableDepth = DepthPrimitive( c: enable, v: depth ); disableDepth = DepthPrimitive( c: disable );
    enableAlarm = AlarmPrimitive( c: enable ); disableAlarm = AlarmPrimitive( c: disable );
}
events { gotoOk; gotoFail; depthOk; depthFail; alarmOk; alarmFail; }
tasks {
    Goto( way-point ): AchieveOneGoal { a: enableGoto -> T0; a: disableGoto -> T1, T6, T7; e: gotoOk -> T2; e: gotoFail -> T3; }
    Depth( depth ): AchieveOneGoal { a: enableDepth -> T0; a: disableDepth -> T1, T6, T7; e: depthOk -> T2; e: depthFail -> T3; }
    Alarm(): AchieveOneGoal { a: enableAlarm -> T0; a: disableAlarm -> T1, T6, T7; e: alarmOk -> T2; e: alarmFail -> T3; }
}
"#;

/// A mission of `calls` task calls: blocks of ten calls mixing sequences,
/// parallels, try-catch and monitors, in one long sequence.
pub fn mission(calls: usize) -> String {
    let mut blocks = Vec::new();
    for b in 0..calls / 10 {
        let d = b % 50;
        blocks.push(format!(
            "try {{ Depth( {d} ) ; parallel {{ Goto( [{b}, 1] ) }} or {{ Depth( {d} ) }} ; Goto( [{b}, 2] ) }} catch {{ Depth( 0 ) }} ; \
             monitor {{ Goto( [{b}, 3] ) ; Depth( 3 ) }} condition ( Alarm() ) do {{ Depth( 0 ) }}"
        ));
    }
    format!("import \"vehicle.mcl\";\nmission {{\n{}\n}}\n", blocks.join(" ;\n"))
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("compile");
    g.sample_size(10);
    for calls in [1_000usize, 10_000, 100_000] {
        let text = mission(calls);
        g.throughput(Throughput::Elements(calls as u64));
        g.bench_with_input(BenchmarkId::from_parameter(calls), &text, |b, text| {
            b.iter(|| {
                let mut db = Database::new();
                let dir = Path::new("/virtual/bench");
                db.set_text(&dir.join("vehicle.mcl"), VEHICLE);
                let f = db.set_text(&dir.join("m.mcl"), text.as_str());
                let missions = compile_file(&db, f).expect("compiles");
                assert_eq!(missions.len(), 1);
                missions
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
