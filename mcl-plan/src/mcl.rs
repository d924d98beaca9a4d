//! The MCL side of planning operators: the `mission Name( params )` and
//! `mcl_plan_op Name( params )` definitions of an .mcl program (a file and
//! everything it imports), and the check that every `:mcl` call of a domain
//! names one of them with the right number of arguments.

use crate::model::McProgram;
use crate::pddl::Domain;
use crate::sexpr::Error;
use mcl_syntax::ast::{Item, MissionKind};
use mcl_syntax::span::LineIndex;
use std::path::{Path, PathBuf};

/// A parametrised mission or mission operator of an .mcl program.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MclOperator {
    pub name: String,
    pub params: Vec<String>,
    /// `mcl_plan_op` (true) or `mission Name( ... )` (false).
    pub plan_op: bool,
    pub file: PathBuf,
    pub line: usize,
}

/// Reads the mission operators of `path` and of the files it imports
/// (transitively, each once: [`McProgram::load`]). Syntax errors and
/// unreadable files are errors (`file:line:column: message`).
pub fn load_operators(path: &Path) -> Result<Vec<MclOperator>, Vec<String>> {
    let program = McProgram::load(path).map_err(|es| es.iter().map(ToString::to_string).collect::<Vec<_>>())?;
    let mut out = Vec::new();
    for f in &program.files {
        let index = LineIndex::new(&f.text);
        for item in &f.items {
            let Item::Mission(m) = item else { continue };
            let Some(name) = &m.name else { continue };
            // A named mission with no parameter list (`mission : auv`) is not an operator.
            if m.kind == MissionKind::PlanOp || !m.params.is_empty() || is_parametrised(&f.text, m) {
                out.push(MclOperator {
                    name: name.text.clone(),
                    params: m.params.iter().map(|n| n.text.clone()).collect(),
                    plan_op: m.kind == MissionKind::PlanOp,
                    file: f.path.clone(),
                    line: index.line_col(&f.text, name.span.start as usize).line as usize,
                });
            }
        }
    }
    Ok(out)
}

/// `mission Name()` (empty parameter list) versus `mission : name`.
fn is_parametrised(text: &str, m: &mcl_syntax::ast::Mission) -> bool {
    let Some(name) = &m.name else { return false };
    text.get(name.span.end as usize..).is_some_and(|rest| rest.trim_start().starts_with('('))
}

/// Checks that every `:mcl` call of the domain names a mission operator of
/// `ops` with as many arguments as it has parameters. Returns the errors and
/// the warnings (actions without `:mcl`, which cannot be run on the vehicle).
pub fn check_mapping(domain: &Domain, ops: &[MclOperator]) -> (Vec<Error>, Vec<String>) {
    let mut errors = Vec::new();
    let mut warnings = Vec::new();
    for a in &domain.actions {
        let Some(m) = &a.mcl else {
            warnings.push(format!(
                "{}:{}: action `{}` has no MCL mission (an `mcl` line, a `pddl_map` mapping or a `:mcl` field): a plan using it cannot run on the vehicle",
                domain.file, a.line, a.name
            ));
            continue;
        };
        match ops.iter().find(|o| o.name == m.name) {
            None => {
                let known: Vec<&str> = ops.iter().map(|o| o.name.as_str()).collect();
                errors.push(Error {
                    file: m.file.clone().unwrap_or_else(|| domain.file.clone()),
                    line: m.line,
                    column: m.column,
                    message: format!(
                        "action `{}` runs the MCL mission `{}`, which the operators file does not define (it defines: {})",
                        a.name,
                        m.name,
                        if known.is_empty() { "nothing".to_string() } else { known.join(", ") }
                    ),
                });
            }
            Some(o) if o.params.len() != m.args.len() => errors.push(Error {
                file: m.file.clone().unwrap_or_else(|| domain.file.clone()),
                line: m.line,
                column: m.column,
                message: format!(
                    "action `{}` calls `{}` with {} argument(s), but `{}` ({}:{}) takes {} ({})",
                    a.name,
                    m.name,
                    m.args.len(),
                    o.name,
                    o.file.display(),
                    o.line,
                    o.params.len(),
                    o.params.join(", ")
                ),
            }),
            Some(_) => {}
        }
    }
    (errors, warnings)
}
