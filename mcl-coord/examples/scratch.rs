use mcl_compiler::{Database, Db};
use mcl_coord::*;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let cut: u32 = std::env::args().nth(2).map(|s| s.parse().unwrap()).unwrap_or(3);
    let db = Database::new();
    let f = db.file(std::path::Path::new(&path));
    let (ms, cs) = source::load(&db, f).unwrap();
    for m in &ms {
        println!(
            "{}: {} places {} transitions, {} activities",
            m.name,
            m.net.place_count(),
            m.net.transition_count(),
            m.activities.len()
        );
        let r = mcl_net::analyze(&m.net, &mcl_net::Options::default());
        println!("  alone: {} states complete {} dead {}", r.states, r.complete, r.dead_markings);
    }
    for c in &cs {
        println!("{c}");
    }
    let plant = centralize(&ms).unwrap();
    if let Ok(only) = std::env::var("ONLY") {
        let cs: Vec<Constraint> = only.split(',').map(|i| cs[i.parse::<usize>().unwrap()].clone()).collect();
        let sups = supervisor::synthesize(&plant, &cs).unwrap();
        let net = supervisor::apply(&plant.net, &sups).unwrap();
        let t = std::time::Instant::now();
        let out = verify::verify(
            &ms,
            &plant,
            &sups,
            &net,
            &verify::VerifyOptions { max_vehicle_states: 3_000_000, ..Default::default() },
        );
        match &out {
            verify::Outcome::Verified(st) => println!("verified {st:?}"),
            verify::Outcome::Unknown(r, st) => println!("unknown {r} {st:?}"),
            verify::Outcome::Problems(w, st) => println!("problems {} {st:?}", w.len()),
        }
        println!("took {:?}", t.elapsed());
        return;
    }
    let sups = supervisor::synthesize(&plant, &cs).unwrap();
    for s in &sups {
        println!("{} : {}  init {}", s.id, s.describe(&plant.net), s.initial);
    }
    let net = supervisor::apply(&plant.net, &sups).unwrap();
    let t = std::time::Instant::now();
    let out = verify::verify(&ms, &plant, &sups, &net, &verify::VerifyOptions::default());
    match &out {
        verify::Outcome::Verified(st) => println!("verified {st:?}"),
        verify::Outcome::Unknown(r, st) => println!("unknown {r} {st:?}"),
        verify::Outcome::Problems(w, st) => {
            println!("problems {st:?}");
            for w in w {
                println!(
                    "{:?} {:?} held {:?}",
                    w.kind,
                    w.path.iter().map(|&t| net.transition(t).unwrap().id.clone()).collect::<Vec<_>>(),
                    w.held.iter().map(|(t, s)| (net.transition(*t).unwrap().id.clone(), s.clone())).collect::<Vec<_>>()
                );
            }
        }
    }
    println!("verify took {:?}", t.elapsed());
    if std::env::var("EXPLORE").is_err() {
        return;
    }
    let t = std::time::Instant::now();
    let ss =
        mcl_net::explore(&net, &mcl_net::Options { cut_above: Some(cut), max_states: 3_000_000, ..Default::default() });
    println!(
        "explored {} states in {:?}, complete {}, dead {}, cut {}",
        ss.len(),
        t.elapsed(),
        ss.complete(),
        ss.dead_states().len(),
        ss.cut_states().len()
    );
    for d in ss.dead_states().take(3) {
        println!("dead: {}", ss.marking(d).display(&net));
    }
}
#[allow(dead_code)]
fn unused() {}
