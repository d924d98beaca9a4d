//! "Did you mean": the known name closest to a misspelt one. One function
//! for every tool that suggests a name (the checker's undefined names, the
//! scenario loader's tasks, labels and events).

/// The candidate closest to `name`, if it is close enough to be a typo
/// (Jaro-Winkler similarity above 0.85, ignoring case; ties go to the
/// smallest name, so the answer does not depend on the candidates' order).
pub fn closest<'n>(name: &str, candidates: impl Iterator<Item = &'n str>) -> Option<&'n str> {
    let lower = name.to_lowercase();
    let mut best: Option<(f64, &str)> = None;
    for c in candidates {
        let score = strsim::jaro_winkler(&lower, &c.to_lowercase());
        if score > 0.85 && best.is_none_or(|(s, b)| score > s || (score == s && c < b)) {
            best = Some((score, c));
        }
    }
    best.map(|(_, c)| c)
}

#[cfg(test)]
mod tests {
    use super::closest;

    #[test]
    fn suggests_a_close_name_only() {
        let names = ["batteryLow", "eventAlarmOk", "Goto"];
        assert_eq!(closest("batteryLo", names.iter().copied()), Some("batteryLow"));
        assert_eq!(closest("gotoo", names.iter().copied()), Some("Goto"));
        assert_eq!(closest("Surface", names.iter().copied()), None);
    }
}
