//! Check + compile of one file, N times in one process, each from a fresh
//! database (the steady state that criterion measures, with a profiler-
//! friendly loop): `cargo run --release -p mcl-compiler --example compile_loop FILE [N]`.
use mcl_compiler::{check_file, compile::compile_file, Database, Db};
fn main() {
    let path = std::env::args().nth(1).expect("usage: compile_loop FILE [N]");
    let n: usize = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    for _ in 0..n {
        let db = Database::new();
        let f = db.file(std::path::Path::new(&path));
        let t = std::time::Instant::now();
        let errors = check_file(&db, f).iter().filter(|d| d.diag.is_error()).count();
        let t_check = t.elapsed();
        let m = compile_file(&db, f).expect("compiles");
        let t_all = t.elapsed();
        let nodes: usize = m.iter().map(|m| m.net.place_count() + m.net.transition_count()).sum();
        drop(m);
        println!(
            "errors {errors}; nodes {nodes}; check {t_check:?}; check+compile {t_all:?}; with drop {:?}",
            t.elapsed()
        );
    }
}
