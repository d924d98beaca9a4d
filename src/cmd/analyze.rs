//! `mcl analyze`: the state space of any PNML net.

use crate::Format;
use mcl_net::{analyze, Options, Semantics};
use std::path::Path;

/// Which firing rule to explore with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SemanticsChoice {
    /// MCL rule for nets with MCL data (events, timers), plain otherwise.
    Auto,
    /// Every enabled transition may fire.
    Plain,
    /// Immediate transitions first; events and timers in tangible markings.
    Mcl,
}

/// How to explore.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// Every reachable marking (the full report).
    Explicit,
    /// Stubborn sets (plain rule only): the deadlock verdict and the number
    /// of dead markings are exact, the state count is the reduced graph's.
    Por,
    /// Decision diagrams by saturation (plain rule only): exact states,
    /// edges, dead markings and bounds without enumerating the markings.
    Symbolic,
}

/// Which place goes to which level of the decision diagram (`--method symbolic`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum OrderChoice {
    /// FORCE: places moved next to the transitions they share.
    Force,
    /// The order of the places in the PNML file.
    Pnml,
}

#[allow(clippy::too_many_arguments)]
pub fn run(
    path: &Path,
    format: Format,
    max_states: usize,
    semantics: SemanticsChoice,
    threads: usize,
    shortest_paths: bool,
    method: Method,
    order: OrderChoice,
) -> u8 {
    let text = match mcl_net::input::read_source(path) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    let net = match mcl_net::read_pnml(&text) {
        Ok(n) => n,
        Err(e) => {
            eprintln!("error: {}: {e}", path.display());
            return 2;
        }
    };
    let semantics = match semantics {
        SemanticsChoice::Plain => Semantics::Plain,
        SemanticsChoice::Mcl => Semantics::Mcl,
        SemanticsChoice::Auto if net.has_non_immediate() => Semantics::Mcl,
        SemanticsChoice::Auto => Semantics::Plain,
    };
    if method == Method::Por {
        return run_por(&net, format, max_states, semantics);
    }
    if method == Method::Symbolic {
        return run_symbolic(&net, format, max_states, semantics, order);
    }
    // Several threads explore without levels (`unordered.rs`) unless
    // shortest paths to the dead markings are asked for.
    let opts = Options { semantics, max_states, threads, exact_order: shortest_paths, ..Options::default() };
    let r = analyze(&net, &opts);
    match format {
        Format::Json => println!("{}", serde_json::to_string_pretty(&r).unwrap_or_else(|_| "{}".into())),
        Format::Human => {
            println!("net `{}`: {} places, {} transitions", net.name(), net.place_count(), net.transition_count());
            let more = if r.complete {
                String::new()
            } else {
                format!(" (stopped at the limit of {max_states} states: the net is larger)")
            };
            println!("reachable markings: {}{more}", r.states);
            println!("edges: {}", r.edges);
            println!("dead markings: {}", r.dead_markings);
            println!("1-safe: {}", if r.one_safe { "yes" } else { "no" });
            println!("largest bound of a place (max_tokens): {}", r.max_tokens);
            println!("most tokens in one marking: {}", r.max_tokens_per_marking);
            for d in r.dead_examples.iter().take(3) {
                let m: Vec<String> =
                    d.marking.iter().map(|(p, k)| if *k == 1 { p.clone() } else { format!("{p}×{k}") }).collect();
                println!(
                    "  dead: {{{}}} after {}",
                    m.join(", "),
                    if d.path_names.is_empty() { "no firing".into() } else { d.path_names.join(" → ") }
                );
            }
        }
    }
    0
}

/// `--method por`: the reduced exploration of `mcl_net::explore::explore_por`.
fn run_por(net: &mcl_net::Net, format: Format, max_states: usize, semantics: Semantics) -> u8 {
    if semantics != Semantics::Plain {
        eprintln!("error: --method por explores with the plain rule only (give --semantics plain)");
        return 2;
    }
    let r = mcl_net::explore::explore_por(net, max_states);
    match format {
        Format::Json => println!("{}", serde_json::to_string_pretty(&r).unwrap_or_else(|_| "{}".into())),
        Format::Human => {
            println!("net `{}`: {} places, {} transitions", net.name(), net.place_count(), net.transition_count());
            let more =
                if r.complete { String::new() } else { format!(" (stopped at the limit of {max_states} states)") };
            println!("states of the reduced graph (stubborn sets): {}{more}", r.states);
            println!("edges of the reduced graph: {}", r.edges);
            println!("dead markings: {}", r.dead_markings);
            println!("deadlock: {}", if r.deadlock { "yes" } else { "no" });
        }
    }
    0
}

/// `--method symbolic`: the decision-diagram exploration of
/// `mcl_net::explore::explore_symbolic`, with `max_states` as its node limit.
fn run_symbolic(net: &mcl_net::Net, format: Format, max_nodes: usize, semantics: Semantics, order: OrderChoice) -> u8 {
    use mcl_net::explore::symbolic::{SymbolicStop, VariableOrder};
    if semantics != Semantics::Plain {
        eprintln!("error: --method symbolic explores with the plain rule only (give --semantics plain)");
        return 2;
    }
    let order = match order {
        OrderChoice::Force => VariableOrder::Force,
        OrderChoice::Pnml => VariableOrder::Pnml,
    };
    let opts = mcl_net::explore::SymbolicOptions { max_nodes, order, ..Default::default() };
    let r = mcl_net::explore::explore_symbolic(net, &opts);
    match format {
        Format::Json => println!("{}", serde_json::to_string_pretty(&r).unwrap_or_else(|_| "{}".into())),
        Format::Human => {
            println!("net `{}`: {} places, {} transitions", net.name(), net.place_count(), net.transition_count());
            match &r.stop {
                Some(SymbolicStop::NodeLimit { max_nodes }) => {
                    println!("incomplete: the diagrams needed more than {max_nodes} nodes (raise --max-states)");
                }
                Some(SymbolicStop::TokenLimit { place, max_tokens }) => {
                    println!("incomplete: place `{place}` would hold more than {max_tokens} tokens (the net may be unbounded)");
                }
                None => {
                    let n = |c: Option<u128>| c.map_or("more than 2^128".to_string(), |c| c.to_string());
                    println!(
                        "reachable markings: {}",
                        r.states.map_or(format!("about {:e}", r.states_approx), |c| c.to_string())
                    );
                    println!("edges: {}", n(r.edges));
                    println!("dead markings: {}", n(r.dead_markings));
                    println!("1-safe: {}", if r.one_safe { "yes" } else { "no" });
                    println!("largest bound of a place (max_tokens): {}", r.max_tokens);
                    println!("most tokens in one marking: {}", r.max_tokens_per_marking);
                    println!("decision diagram: {} nodes ({} created)", r.mdd_nodes, r.nodes_created);
                    if let Some(d) = &r.dead_example {
                        let m: Vec<String> = d
                            .marking
                            .iter()
                            .map(|(p, k)| if *k == 1 { p.clone() } else { format!("{p}×{k}") })
                            .collect();
                        println!(
                            "  dead: {{{}}} after {}",
                            m.join(", "),
                            if d.path_names.is_empty() { "no firing".into() } else { d.path_names.join(" → ") }
                        );
                    }
                }
            }
        }
    }
    0
}
