//! Feeds arbitrary bytes (decoded as lossy UTF-8) to the parser. The parser
//! must never panic, and every span it reports must lie within the text, on
//! character boundaries.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let p = mcl_syntax::parse(&text);
    for d in &p.errors {
        for s in std::iter::once(d.span).chain(d.labels.iter().map(|l| l.span)) {
            assert!(s.start <= s.end && s.end as usize <= text.len(), "span {s:?} out of the text");
            assert!(text.is_char_boundary(s.start as usize) && text.is_char_boundary(s.end as usize), "span {s:?} not on char boundaries");
        }
    }
    for c in &p.comments {
        assert!(c.span.end as usize <= text.len());
    }
    for item in &p.file.items {
        assert!(item.span().end as usize <= text.len());
    }
});
