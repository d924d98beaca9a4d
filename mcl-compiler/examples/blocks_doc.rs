//! Regenerates the drawings of docs/blocks.md: for every task pattern of the
//! standard library (with events bound as a task would), the call adapter
//! and every control structure (with reduced blocks plugged in), its net in
//! its verification harness (`NAME.dot`) and, when small enough, its
//! reachability graph (`NAME-rg.dot`), plus a table of state counts. `cargo run -p mcl-compiler --example blocks_doc -- docs/blocks`
//! then `for f in docs/blocks/*.dot; do dot -Tsvg "$f" -o "${f%.dot}.svg"; done`.

use mcl_compiler::compile::builder::Builder;
use mcl_compiler::compile::dot::to_dot;
use mcl_compiler::compile::structures::Structure;
use mcl_compiler::compile::verify::{call_adapter_harness, structure_harness, task_harness, Child, Harness};
use mcl_compiler::{scope, Database};
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
    let write = |name: &str, h: &Harness| {
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
    };
    println!("| block | places | transitions | states (tangible) in its harness | verified |");
    println!("|---|---:|---:|---:|---|");
    // The task patterns of the standard library, bound as a task binds them.
    let mut db = Database::new();
    let file = db.set_text(
        std::path::Path::new("/virtual/blocks_doc/tasks.mcl"),
        r#"
        actions { enableX = XPrimitive( c: enable ); disableX = XPrimitive( c: disable ); }
        events { xOk; xFail; }
        tasks {
            Goal(): AchieveOneGoal { a: enableX -> T0; a: disableX -> T1, T6, T7; e: xOk -> T2; e: xFail -> T3; }
            GoalTimed( timeout ): AchieveOneGoalTimed { a: enableX -> T0; a: disableX -> T1, T6, T7; e: xOk -> T2; e: xFail -> T3; }
            Now(): Instant { }
        }
        "#,
    );
    let sc = scope::scope(&db, file);
    for (name, task) in [("achieve-one-goal", "Goal"), ("achieve-one-goal-timed", "GoalTimed"), ("instant", "Now")] {
        let mut b = Builder::new(task);
        mcl_compiler::compile::add_task_net(&db, sc, &mut b, task, "").expect("std pattern").expect(task);
        let net = b.finish().build().expect("std pattern net");
        write(name, &task_harness(&net).expect("interface"));
    }
    write("call-adapter", &call_adapter_harness());
    for (name, s) in all {
        write(name, &structure_harness(&s, &[Child::Reduced]));
    }
}
