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

use crate::model::{Net, PlaceId};
use crate::structural::{p_invariants, Limits};

/// Cap on the rows of the semiflow computation: grouping is an
/// optimisation, a net whose semiflows are expensive is not grouped.
const MAX_ROWS: usize = 2_000;

/// The places of one level.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Unit {
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
pub(super) fn units(net: &Net, group: bool) -> Vec<Unit> {
    let mut in_group = vec![false; net.place_count()];
    let mut groups: Vec<Vec<PlaceId>> = Vec::new();
    if group && net.place_count() > 1 {
        let m0 = net.initial_marking();
        let limits = Limits { max_rows: MAX_ROWS, ..Limits::default() };
        let mut flows: Vec<Vec<PlaceId>> = p_invariants(net, &limits)
            .invariants
            .into_iter()
            .filter(|inv| inv.iter().all(|&(_, w)| w == 1))
            .filter(|inv| inv.iter().map(|&(p, _)| u64::from(m0.get(p))).sum::<u64>() == 1)
            .map(|inv| inv.into_iter().map(|(p, _)| p).collect())
            .collect();
        flows.sort_by_key(|f: &Vec<PlaceId>| std::cmp::Reverse(f.len()));
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
}
