//! Times check and compile of one file: `cargo run --release -p mcl-compiler --example compile_time FILE`.
use mcl_compiler::{check_file, compile::compile_file, Database, Db};
fn main() {
    let path = std::env::args().nth(1).expect("usage: compile_time FILE");
    let db = Database::new();
    let f = db.file(std::path::Path::new(&path));
    let t = std::time::Instant::now();
    let errors = check_file(&db, f).iter().filter(|d| d.diag.is_error()).count();
    let t_check = t.elapsed();
    let m = compile_file(&db, f).expect("compiles");
    let t_all = t.elapsed();
    let pnml = mcl_net::write_pnml(&m[0].net).expect("pnml");
    println!(
        "errors {errors}; check {t_check:?}; check+compile {t_all:?}; pnml {:?} ({} bytes)",
        t.elapsed() - t_all,
        pnml.len()
    );
}
