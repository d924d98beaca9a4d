//! Graphviz rendering of a compiled net: one cluster per control structure
//! (nested as in the mission), one per call adapter, one per task net.

use mcl_net::{Net, NodeId, Provenance, TransitionKind};
use std::collections::BTreeMap;
use std::fmt::Write;

/// Where a node is drawn: the chain of clusters it belongs to.
fn cluster_path(p: &Provenance) -> Vec<String> {
    if let (Some(task), None) = (&p.task, p.call_site) {
        return vec![format!("task {task}")];
    }
    let mut out = Vec::new();
    if let Some(path) = &p.path {
        let parts: Vec<&str> = path.split('.').collect();
        for i in 1..=parts.len() {
            out.push(parts[..i].join("."));
        }
    }
    if let Some(c) = p.call_site {
        out.push(format!("call {c}"));
    }
    out
}

#[derive(Default)]
struct Cluster {
    nodes: Vec<String>,
    children: BTreeMap<String, Cluster>,
}

fn esc(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"").replace('\n', "\\n")
}

/// The last component of a node id, for compact labels.
fn short(id: &str) -> &str {
    id.rsplit('.').next().unwrap_or(id)
}

/// Renders `net` in the DOT language.
pub fn to_dot(net: &Net) -> String {
    let mut root = Cluster::default();
    let mut labels: BTreeMap<String, String> = BTreeMap::new();
    let put = |prov: &Provenance, line: String, root: &mut Cluster, labels: &mut BTreeMap<String, String>| {
        let mut c = root;
        for key in cluster_path(prov) {
            if !labels.contains_key(&key) {
                let label = match (&prov.structure, prov.call_site, &prov.task) {
                    _ if key.starts_with("task ") => key.clone(),
                    (_, Some(_), Some(t)) if key.starts_with("call ") => format!("{t}(…)"),
                    (Some(s), _, _) if Some(&key) == prov.path.as_ref() => s.clone(),
                    _ => String::new(),
                };
                if !label.is_empty() {
                    labels.insert(key.clone(), label);
                }
            }
            c = c.children.entry(key).or_default();
        }
        c.nodes.push(line);
    };
    for p in net.places() {
        let tokens = if p.initial > 0 { "●".repeat(p.initial.min(3) as usize) } else { String::new() };
        let line = format!(
            "\"{}\" [shape=circle, width=0.35, fixedsize=false, label=\"{}\n{}\", tooltip=\"{}\"];",
            esc(&p.id),
            esc(short(&p.id)),
            tokens,
            esc(&p.id)
        );
        put(&p.provenance, line, &mut root, &mut labels);
    }
    for t in net.transitions() {
        let mut label = short(&t.id).to_string();
        let (style, color) = match &t.kind {
            TransitionKind::Immediate => ("filled", "black"),
            TransitionKind::Event(e) => {
                let _ = write!(label, "\n?{e}");
                ("filled", "royalblue")
            }
            TransitionKind::Timed(d) => {
                let _ = match d {
                    mcl_net::Delay::Fixed(s) if *s == 0.0 => write!(label, "\n(deferred)"),
                    mcl_net::Delay::Fixed(s) => write!(label, "\n⏱{s}s"),
                    mcl_net::Delay::Param(p) => write!(label, "\n⏱{p}"),
                };
                ("filled", "darkorange")
            }
        };
        for a in &t.actions {
            let _ = write!(label, "\n!{}", a.action);
        }
        let line = format!(
            "\"{}\" [shape=box, height=0.1, style={style}, fillcolor=\"{color}\", fontcolor=white, fontsize=9, label=\"{}\", tooltip=\"{}\"];",
            esc(&t.id),
            esc(&label),
            esc(&t.id)
        );
        put(&t.provenance, line, &mut root, &mut labels);
    }
    let mut out = String::new();
    let _ = writeln!(out, "digraph \"{}\" {{", esc(net.name()));
    let _ = writeln!(out, "  rankdir=TB; compound=true; fontname=\"Helvetica\"; node [fontname=\"Helvetica\", fontsize=10]; edge [arrowsize=0.6];");
    fn emit(out: &mut String, c: &Cluster, labels: &BTreeMap<String, String>, depth: usize, counter: &mut usize) {
        let pad = "  ".repeat(depth + 1);
        for n in &c.nodes {
            let _ = writeln!(out, "{pad}{n}");
        }
        for (key, child) in &c.children {
            *counter += 1;
            let _ = writeln!(out, "{pad}subgraph cluster_{counter} {{");
            let label = labels.get(key).cloned().unwrap_or_default();
            let style = if key.starts_with("task ") {
                "style=\"filled\"; fillcolor=\"#eef5ff\""
            } else if key.starts_with("call ") {
                "style=\"dashed\""
            } else {
                "style=\"rounded\""
            };
            let _ = writeln!(out, "{pad}  label=\"{}\"; {style}; fontsize=11;", esc(&label));
            emit(out, child, labels, depth + 1, counter);
            let _ = writeln!(out, "{pad}}}");
        }
    }
    let mut counter = 0;
    emit(&mut out, &root, &labels, 0, &mut counter);
    for a in net.arcs() {
        let (src, dst, w) = match *a {
            mcl_net::Arc::Input { place, transition, weight } => {
                (NodeId::Place(place), NodeId::Transition(transition), weight)
            }
            mcl_net::Arc::Output { transition, place, weight } => {
                (NodeId::Transition(transition), NodeId::Place(place), weight)
            }
        };
        let id = |n: NodeId| match n {
            NodeId::Place(p) => net.place(p).map(|x| x.id.to_string()).unwrap_or_default(),
            NodeId::Transition(t) => net.transition(t).map(|x| x.id.to_string()).unwrap_or_default(),
        };
        let label = if w > 1 { format!(" [label=\"{w}\"]") } else { String::new() };
        let _ = writeln!(out, "  \"{}\" -> \"{}\"{label};", esc(&id(src)), esc(&id(dst)));
    }
    out.push_str("}\n");
    out
}
