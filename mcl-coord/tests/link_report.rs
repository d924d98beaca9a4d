//! The link report (`mcl_coord::link_report`, `mcl compile --link-report`):
//! message counts and sizes of the seed's AUV/ASC mission, every message in
//! a 32-byte frame, and E0410's explanation (its example does not fit a
//! 1-byte frame, its fix does).

use mcl_compiler::{codes, Database};
use mcl_coord::link_report::{link_report, Count, LinkReport};
use std::path::{Path, PathBuf};

const VEHICLE: &str = include_str!("../../examples/vehicle.mcl");

/// The link report of `src` (next to `vehicle.mcl`).
fn report_of(name: &str, src: &str) -> LinkReport {
    let mut db = Database::new();
    let d = Path::new("/virtual/link-report").join(name);
    db.set_text(&d.join("vehicle.mcl"), VEHICLE);
    let f = db.set_text(&d.join("m.mcl"), src);
    report_of_file(&db, f)
}

fn report_of_file(db: &Database, f: mcl_compiler::SourceFile) -> LinkReport {
    let (missions, constraints) = mcl_coord::source::load(db, f).expect("it compiles");
    let r = mcl_coord::analyze(&missions, &constraints).expect("it is analysed");
    assert!(r.deadlock_free, "{:?}", r.problems);
    let vehicles = mcl_coord::decentralize(&missions, &r.supervisors).expect("vehicle nets");
    link_report(&missions, &constraints, &vehicles)
}

#[test]
fn every_message_of_the_auv_asc_mission_fits_a_32_byte_frame() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/auv-asc.mcl");
    let db = Database::new();
    let f = mcl_compiler::Db::file(&db, &path);
    let r = report_of_file(&db, f);
    assert!(r.frame_bytes <= 32 && r.frame_diagnostics(32).is_empty(), "{}", r.to_text());
    assert!(!r.messages.is_empty() && r.messages.iter().all(|m| m.compact_bytes == r.frame_bytes));
    // Kind 2 bits, two missions (1 bit each), the AUV tells 7 firings,
    // with "ended" 8 entries (3 bits), 3 bits of sequence.
    assert_eq!(r.frame_bits, 2 + 2 + 3 + 3, "{}", r.to_text());
    assert_eq!(r.constraints.len(), 7);
    // The first order sends the ASC's end of `deploy_auv` once; the order
    // inside the ASC's loop is unbounded, and says why.
    assert_eq!(r.constraints[0].messages, Count::Bounded { max: 1 }, "{}", r.to_text());
    assert_eq!(r.constraints[0].compact_bytes, Count::Bounded { max: r.frame_bytes });
    assert!(matches!(&r.constraints[1].messages, Count::Unbounded { reason, .. } if reason.contains("loop")));
    for c in &r.constraints[4..] {
        assert_eq!(c.messages, Count::Bounded { max: 1 }, "{}: {}", c.text, r.to_text());
        let json = c.json_bytes.max().expect("bounded");
        assert!(json > 20 * r.frame_bytes, "JSON takes {json} bytes");
    }
    let text = r.to_text();
    assert!(text.contains("1. order { asc:deploy_auv, auv:deploy_auv }: messages 1, bytes 2 / 70"), "{text}");
    // A frame of the report's size is an error below it, at every constraint with messages.
    let d = r.frame_diagnostics(r.frame_bytes - 1);
    assert_eq!(d.len(), 7);
    assert!(d.iter().all(|d| d.code == codes::FRAME_TOO_SMALL));
}

/// The ```mcl block of a `## name` section.
fn example(md: &str, name: &str) -> String {
    let start = md.find(&format!("\n## {name}\n")).unwrap_or_else(|| panic!("no ## {name}"));
    let rest = &md[start + 1..];
    let rest = &rest[rest.find("```mcl\n").expect("an mcl block") + 7..];
    rest[..rest.find("```").expect("closed block")].to_string()
}

#[test]
fn the_explanation_of_e0410_holds_at_one_byte() {
    for &code in codes::LINK {
        let info = codes::lookup(code).unwrap();
        let r = report_of("example", &example(info.explanation, "Example"));
        let d = r.frame_diagnostics(1);
        assert_eq!((r.frame_bits, d.len()), (9, 2), "{}", r.to_text());
        assert!(d[0].message.contains("do not fit a 1-byte frame"), "{:?}", d[0]);
        let r = report_of("fix", &example(info.explanation, "Fix"));
        assert_eq!(r.frame_bits, 8, "{}", r.to_text());
        assert!(r.frame_diagnostics(1).is_empty());
    }
}
