//! Regenerates the drawings of docs/blocks.md: for every control structure,
//! its net with reduced blocks plugged in (`NAME.dot`) and, when small
//! enough, its reachability graph (`NAME-rg.dot`), plus a table of state
//! counts. `cargo run -p mcl-compiler --example blocks_doc -- docs/blocks`
//! then `for f in docs/blocks/*.dot; do dot -Tsvg "$f" -o "${f%.dot}.svg"; done`.

use mcl_compiler::compile::dot::to_dot;
use mcl_compiler::compile::structures::Structure;
use mcl_compiler::compile::verify::{structure_harness, Child};
use mcl_syntax::ast::MonitorKind;

fn main() {
    let out = std::path::PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "docs/blocks".into()));
    std::fs::create_dir_all(&out).expect("output folder");
    let all = [
        ("not", Structure::Not),
        ("sequence", Structure::Sequence(2)),
        ("if-then", Structure::IfThen),
        ("if-then-else", Structure::IfThenElse),
        ("while-do", Structure::While),
        ("try-catch", Structure::TryCatch),
        ("parallel-and", Structure::ParallelAnd(2)),
        ("parallel-or", Structure::ParallelOr(2)),
        ("monitor-condition-do", Structure::Monitor(vec![MonitorKind::Condition])),
        ("monitor-while_condition-do", Structure::Monitor(vec![MonitorKind::WhileCondition])),
    ];
    println!("| structure | places | transitions | states (tangible) with reduced children | verified |");
    println!("|---|---:|---:|---:|---|");
    for (name, s) in all {
        let h = structure_harness(&s, &[Child::Reduced]);
        let v = h.verify(1_000_000);
        std::fs::write(out.join(format!("{name}.dot")), to_dot(&h.net)).expect("write");
        if let Some(rg) = h.reachability_dot(80) {
            std::fs::write(out.join(format!("{name}-rg.dot")), rg).expect("write");
        }
        println!(
            "| {name} | {} | {} | {} ({}) | {} |",
            h.net.place_count(),
            h.net.transition_count(),
            v.states,
            v.tangible,
            if v.ok() { "yes" } else { "NO" }
        );
    }
}
