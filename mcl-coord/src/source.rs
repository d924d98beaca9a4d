//! Missions and constraints read from an MCL program (seed 6.4, Extract
//! 6.5): every mission of the file, compiled, and every constraint of its
//! `constraints { ... }` blocks.

use mcl_compiler::compile::{compile_file, CompileError};
use mcl_compiler::{Db, SourceFile};
use mcl_syntax::ast::{self, Item};

use crate::model::{CallRef, Constraint, ConstraintKind, Mission};

/// The compiled missions of `file` (in source order, named as written; an
/// anonymous mission is `mission`) and the constraints of its constraints
/// blocks. A bare `label` is given the only mission that has a call with
/// that label (the checker rejects ambiguous and unknown labels).
pub fn load(db: &dyn Db, file: SourceFile) -> Result<(Vec<Mission>, Vec<Constraint>), CompileError> {
    let compiled = compile_file(db, file)?;
    let missions: Vec<Mission> = compiled.into_iter().map(|m| Mission::from_compiled(m.name, m.net)).collect();
    let mut constraints = Vec::new();
    for item in &mcl_compiler::parse(db, file).file.items {
        let Item::Constraints(block) = item else { continue };
        for c in &block.constraints {
            constraints.push(convert(c, &missions));
        }
    }
    Ok((missions, constraints))
}

fn convert(c: &ast::Constraint, missions: &[Mission]) -> Constraint {
    let kind = match c.kind {
        ast::ConstraintKind::Mutex => {
            ConstraintKind::Mutex { bound: c.bound.as_ref().and_then(|b| b.as_u32()).unwrap_or(1) }
        }
        ast::ConstraintKind::Order => ConstraintKind::Order,
        ast::ConstraintKind::Sync => ConstraintKind::Sync,
    };
    let calls = c
        .refs
        .iter()
        .map(|r| {
            let mission = match &r.mission {
                Some(m) => m.text.clone(),
                None => missions
                    .iter()
                    .find(|m| m.activities.iter().any(|a| a.label == r.label.text))
                    .map(|m| m.name.clone())
                    .unwrap_or_default(),
            };
            CallRef { mission, label: r.label.text.clone() }
        })
        .collect();
    Constraint { kind, calls, span: Some((c.span.start, c.span.end)) }
}
