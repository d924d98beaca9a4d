//! Levels of the diagram: which places share a level and how a level's
//! value encodes their tokens.
//!
//! A P-semiflow with unit weights and one token in the initial marking
//! keeps exactly one token on its places: they are mutually exclusive and
//! 1-bounded, and so is any subset of them. Such a set (a *group*) becomes
//! one level whose value says which of its places is marked (0: none, `i`:
//! the `i`-th). Every other place is a level of its own whose value is its
//! token count. Groups cut the number of levels and turn the transitions
//! that move a token inside a group into changes of one level (a processor's
//! states, a bus and the accesses it serves in SharedMemory).

use rustc_hash::{FxHashMap, FxHashSet};

use crate::model::{Net, PlaceId};

/// Cap on the rows of the semiflow computation: grouping is an
/// optimisation, a net whose semiflows are expensive is grouped only by
/// those found before the cap.
const MAX_ROWS: usize = 20_000;

/// Cap on the pairs of rows examined, for the same reason.
const MAX_PAIRS: usize = 20_000_000;

/// The places of one level.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Unit {
    /// One place; the value is its token count.
    Place(PlaceId),
    /// Mutually exclusive 1-bounded places; the value is 0 when none is
    /// marked, `i` when the `i`-th (from 1) holds the token.
    Group(Vec<PlaceId>),
}

impl Unit {
    /// The places of the unit.
    pub fn places(&self) -> &[PlaceId] {
        match self {
            Unit::Place(p) => std::slice::from_ref(p),
            Unit::Group(g) => g,
        }
    }
}

/// The units of `net`: with `group`, the mutually exclusive sets found from
/// unit-weight P-semiflows with one initial token (largest first, each place
/// in at most one group), every other place alone; without, one unit per
/// place. Units come in the order of their first place.
pub(crate) fn units(net: &Net, group: bool) -> Vec<Unit> {
    let mut in_group = vec![false; net.place_count()];
    let mut groups: Vec<Vec<PlaceId>> = Vec::new();
    if group {
        let mut flows = unit_semiflows(net);
        flows.sort_by_key(|f| std::cmp::Reverse(f.len()));
        for flow in flows {
            let rest: Vec<PlaceId> = flow.into_iter().filter(|p| !in_group[p.index()]).collect();
            if rest.len() >= 2 {
                for p in &rest {
                    in_group[p.index()] = true;
                }
                groups.push(rest);
            }
        }
    }
    let mut units: Vec<Unit> = groups.into_iter().map(Unit::Group).collect();
    units.extend(net.place_ids().filter(|p| !in_group[p.index()]).map(Unit::Place));
    for u in &mut units {
        if let Unit::Group(g) = u {
            g.sort_unstable();
        }
    }
    units.sort_by_key(|u| u.places()[0]);
    units
}

/// One row of the Farkas tableau restricted to 0/1 weights: the places `y`
/// (sorted), their initial tokens, and `c = y·C` (sparse, by transition).
#[derive(Clone)]
struct Row {
    c: Vec<(u32, i64)>,
    y: Vec<u32>,
    tokens: u32,
}

/// Unit-weight P-semiflows of `net` holding one initial token: the Farkas
/// algorithm (columns eliminated fewest-pairs first) keeping only rows with
/// 0/1 weights and at most one token, i.e. combining two rows only when
/// their coefficients cancel one for one, their places are disjoint and
/// they hold one token between them. It may miss some such semiflows (a
/// weighted intermediate row, or the caps [`MAX_ROWS`] and [`MAX_PAIRS`]
/// hit: then only the rows already solved count); every one it returns is
/// a semiflow.
fn unit_semiflows(net: &Net) -> Vec<Vec<PlaceId>> {
    let m0 = net.initial_marking();
    let mut c: Vec<FxHashMap<u32, i64>> = vec![FxHashMap::default(); net.place_count()];
    for t in net.transition_ids() {
        for &(p, w) in net.pre(t) {
            *c[p.index()].entry(t.index() as u32).or_default() -= i64::from(w);
        }
        for &(p, w) in net.post(t) {
            *c[p.index()].entry(t.index() as u32).or_default() += i64::from(w);
        }
    }
    let mut rows: Vec<Row> = net
        .place_ids()
        .filter(|&p| m0.get(p) <= 1)
        .map(|p| {
            let mut c: Vec<(u32, i64)> = c[p.index()].iter().filter(|e| *e.1 != 0).map(|(&t, &v)| (t, v)).collect();
            c.sort_unstable();
            Row { c, y: vec![p.index() as u32], tokens: m0.get(p) }
        })
        .collect();
    let mut pairs = 0usize;
    loop {
        // The column with the fewest (positive, negative) pairs.
        let mut sign: FxHashMap<u32, (usize, usize)> = FxHashMap::default();
        for r in &rows {
            for &(t, v) in &r.c {
                let e = sign.entry(t).or_default();
                if v > 0 {
                    e.0 += 1;
                } else {
                    e.1 += 1;
                }
            }
        }
        let Some((&col, _)) = sign.iter().min_by_key(|(&t, &(pos, neg))| (pos * neg, t)) else { break };
        let at = |r: &Row| r.c.binary_search_by_key(&col, |&(t, _)| t).map_or(0, |i| r.c[i].1);
        let (mut next, mut pos, mut neg) = (Vec::new(), Vec::new(), Vec::new());
        for r in rows {
            match at(&r) {
                0 => next.push(r),
                v if v > 0 => pos.push(r),
                _ => neg.push(r),
            }
        }
        let mut seen: FxHashSet<Vec<u32>> = next.iter().map(|r| r.y.clone()).collect();
        'pairs: for p in &pos {
            for n in &neg {
                pairs += 1;
                if pairs > MAX_PAIRS {
                    break 'pairs;
                }
                if at(p) != -at(n) || p.tokens + n.tokens > 1 || !disjoint(&p.y, &n.y) {
                    continue;
                }
                let mut y: Vec<u32> = p.y.iter().chain(&n.y).copied().collect();
                y.sort_unstable();
                if !seen.insert(y.clone()) {
                    continue;
                }
                next.push(Row { c: add(&p.c, &n.c), y, tokens: p.tokens + n.tokens });
                if next.len() > MAX_ROWS {
                    break 'pairs;
                }
            }
        }
        rows = next;
        if rows.len() > MAX_ROWS || pairs > MAX_PAIRS {
            rows.retain(|r| r.c.is_empty());
            break;
        }
    }
    rows.into_iter()
        .filter(|r| r.c.is_empty() && r.tokens == 1)
        .map(|r| r.y.into_iter().map(PlaceId).collect())
        .collect()
}

/// Whether two sorted lists share no element.
fn disjoint(a: &[u32], b: &[u32]) -> bool {
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => return false,
        }
    }
    true
}

/// `a + b` for sparse sorted vectors (zeros dropped).
fn add(a: &[(u32, i64)], b: &[(u32, i64)]) -> Vec<(u32, i64)> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let e = match (a.get(i), b.get(j)) {
            (Some(&x), Some(&y)) if x.0 == y.0 => {
                i += 1;
                j += 1;
                (x.0, x.1 + y.1)
            }
            (Some(&x), Some(&y)) if x.0 < y.0 => {
                i += 1;
                x
            }
            (Some(&x), None) => {
                i += 1;
                x
            }
            (_, Some(&y)) => {
                j += 1;
                y
            }
            (None, None) => break,
        };
        if e.1 != 0 {
            out.push(e);
        }
    }
    out
}

/// The units in level order and where each place sits.
#[derive(Clone, Debug)]
pub(super) struct Layout {
    /// `units[i]` sits at level `levels - i` (top level first).
    pub units: Vec<Unit>,
    /// Level of each place.
    pub level_of: Vec<u32>,
    /// Index of each place in its unit.
    pub slot_of: Vec<u32>,
}

impl Layout {
    /// The layout of `units`, top level first; `places` is the place count.
    pub fn new(units: Vec<Unit>, places: usize) -> Layout {
        let levels = units.len() as u32;
        let mut level_of = vec![0; places];
        let mut slot_of = vec![0; places];
        for (i, u) in units.iter().enumerate() {
            for (s, p) in u.places().iter().enumerate() {
                level_of[p.index()] = levels - i as u32;
                slot_of[p.index()] = s as u32;
            }
        }
        Layout { units, level_of, slot_of }
    }

    /// Number of levels.
    pub fn levels(&self) -> u32 {
        self.units.len() as u32
    }

    /// The unit at `level` (1..=levels).
    pub fn unit(&self, level: u32) -> &Unit {
        &self.units[(self.levels() - level) as usize]
    }

    /// Tokens that value `v` of `level` puts on the `slot`-th place of the unit.
    pub fn tokens(&self, level: u32, v: u32, slot: u32) -> u32 {
        match self.unit(level) {
            Unit::Place(_) => v,
            Unit::Group(_) => u32::from(v == slot + 1),
        }
    }

    /// Tokens that value `v` of `level` puts on all places of the unit.
    pub fn total(&self, level: u32, v: u32) -> u32 {
        match self.unit(level) {
            Unit::Place(_) => v,
            Unit::Group(_) => u32::from(v > 0),
        }
    }

    /// The marking (tokens per place, net order) of a tuple (top level first).
    pub fn decode(&self, tuple: &[u32]) -> Vec<u32> {
        let mut m = vec![0; self.level_of.len()];
        for (u, &v) in self.units.iter().zip(tuple) {
            match u {
                Unit::Place(p) => m[p.index()] = v,
                Unit::Group(g) => {
                    if let Some(p) = (v as usize).checked_sub(1).and_then(|i| g.get(i)) {
                        m[p.index()] = 1;
                    }
                }
            }
        }
        m
    }

    /// The tuple (top level first) of a marking (tokens per place, net
    /// order); `None` when a group would hold more than one token.
    pub fn encode(&self, m: &[u32]) -> Option<Vec<u32>> {
        self.units
            .iter()
            .map(|u| match u {
                Unit::Place(p) => Some(m[p.index()]),
                Unit::Group(g) => {
                    let mut v = 0;
                    for (i, p) in g.iter().enumerate() {
                        match m[p.index()] {
                            0 => {}
                            1 if v == 0 => v = i as u32 + 1,
                            _ => return None,
                        }
                    }
                    Some(v)
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{NetBuilder, Place, Transition};

    #[test]
    fn a_one_token_cycle_is_one_group_and_codes_round_trip() {
        // a -> b -> c -> a with one token, and an unrelated counter d.
        let mut b = NetBuilder::new("cycle");
        let ps: Vec<PlaceId> =
            ["a", "b", "c"].iter().map(|n| b.add_place(Place::new(*n).with_tokens(u32::from(*n == "a")))).collect();
        let d = b.add_place(Place::new("d"));
        for i in 0..3 {
            let t = b.add_transition(Transition::new(format!("t{i}")));
            b.add_input(ps[i], t, 1).add_output(t, ps[(i + 1) % 3], 1);
        }
        let t = b.add_transition(Transition::new("inc"));
        b.add_output(t, d, 1);
        let net = b.build().unwrap();
        assert_eq!(units(&net, false).len(), 4);
        let units = units(&net, true);
        assert_eq!(units, vec![Unit::Group(ps.clone()), Unit::Place(d)]);
        let layout = Layout::new(units, 4);
        assert_eq!(layout.encode(&[0, 1, 0, 7]), Some(vec![2, 7]));
        assert_eq!(layout.decode(&[2, 7]), vec![0, 1, 0, 7]);
        assert_eq!(layout.encode(&[1, 1, 0, 0]), None);
        assert_eq!((layout.level_of[d.index()], layout.slot_of[ps[2].index()]), (1, 2));
    }

    /// On SharedMemory-5 every flow found keeps its token sum under every
    /// transition and holds one token; the bus with its 20 accesses and
    /// each processor's three other states become groups.
    #[test]
    fn shared_memory_groups_are_one_token_semiflows() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/mcc/SharedMemory-PT-000005.pnml");
        let net = crate::read_pnml(&std::fs::read_to_string(path).unwrap()).unwrap();
        let m0 = net.initial_marking();
        let flows = unit_semiflows(&net);
        assert!(!flows.is_empty());
        for f in &flows {
            assert_eq!(f.iter().map(|&p| m0.get(p)).sum::<u32>(), 1);
            for t in net.transition_ids() {
                let d: i64 = net.delta(t).iter().filter(|(p, _)| f.contains(p)).map(|&(_, d)| d).sum();
                assert_eq!(d, 0, "{t:?} changes {f:?}");
            }
        }
        let sizes: Vec<usize> = units(&net, true)
            .iter()
            .filter_map(|u| match u {
                Unit::Group(g) => Some(g.len()),
                Unit::Place(_) => None,
            })
            .collect();
        assert_eq!(sizes.iter().filter(|&&n| n == 21).count(), 1, "{sizes:?}");
        assert_eq!(sizes.iter().filter(|&&n| n == 3).count(), 5, "{sizes:?}");
    }

    /// A cycle holding two tokens, or one whose token a transition can
    /// destroy, is not a group.
    #[test]
    fn no_group_without_a_one_token_semiflow() {
        for (tokens, leak) in [(2, false), (1, true)] {
            let mut b = NetBuilder::new("cycle");
            let x = b.add_place(Place::new("x").with_tokens(tokens));
            let y = b.add_place(Place::new("y"));
            let t = b.add_transition(Transition::new("t"));
            b.add_input(x, t, 1).add_output(t, y, 1);
            let u = b.add_transition(Transition::new("u"));
            b.add_input(y, u, 1).add_output(u, x, 1);
            if leak {
                let l = b.add_transition(Transition::new("leak"));
                b.add_input(y, l, 1);
            }
            let net = b.build().unwrap();
            assert_eq!(units(&net, true), vec![Unit::Place(x), Unit::Place(y)]);
        }
    }
}
