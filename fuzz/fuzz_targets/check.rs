//! Feeds arbitrary bytes (decoded as lossy UTF-8) to the whole front end as
//! `mcl check` runs it: the salsa database's `check_file` (imports, names,
//! tasks, patterns, missions, constraints, block verification), then the
//! formatter. Nothing may panic and every diagnostic span must lie within
//! the text, on character boundaries. Seed it with the corpus:
//! `cargo fuzz run check ../examples ../tests/ui ../mcl-syntax/tests/bad`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mcl_compiler::{check_file, Database};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data).into_owned();
    let mut db = Database::new();
    let file = db.set_text(Path::new("/fuzz/mission.mcl"), text.as_str());
    for fd in check_file(&db, file).iter() {
        let d = &fd.diag;
        for s in std::iter::once(d.span).chain(d.labels.iter().filter(|l| l.file.is_none()).map(|l| l.span)) {
            assert!(s.start <= s.end && s.end as usize <= text.len(), "{}: span {s:?} out of the text", d.code);
            assert!(
                text.is_char_boundary(s.start as usize) && text.is_char_boundary(s.end as usize),
                "{}: span {s:?} not on char boundaries",
                d.code
            );
        }
    }
    let _ = mcl_syntax::format::format(&text);
});
