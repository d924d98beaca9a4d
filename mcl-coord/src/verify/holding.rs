//! A proof of freedom from what each vehicle holds (docs/coordination.md,
//! "Holdings"): a compositional rule for groups whose supervisors are all
//! resources that a vehicle takes and gives back (mutexes), loops or not.
//!
//! Premises, checked on the reduced vehicle graphs and the group's effects
//! (the graphs the product explores):
//!
//! * H1, **holdings**: no effect takes back, and each vehicle `v` has a
//!   *holding* `h_v(c) ≥ 0` per class `c` and supervisor place, with
//!   `h_v = 0` at its initial class and `h_v(c') = h_v(c) + consumed −
//!   produced` along every edge. Then every state of the product has
//!   count(s) = initial(s) − Σ_v h_v(c_v)(s): exact counts, never above the
//!   initial one (never `>K`), and a class whose holding exceeds the
//!   initial count is never reached.
//! * H2, **no hold and wait**: every class with a nonzero holding is in the
//!   *attractor* of the classes holding nothing: whatever the counts
//!   allowed (each from 0 to initial − h_v(c)), some edge of the vehicle is
//!   enabled there, under the product's rule (a blocked edge waits while an
//!   urgent gate is allowed), and leads one step closer. A vehicle that
//!   holds something can give it all back alone, while the others stand
//!   still at any counts in that range.
//! * H3, **alone**: with counts initial − h_v (the others hold nothing),
//!   from every class holding nothing the vehicle alone reaches an end
//!   class holding nothing when it can end alone, and otherwise is at an
//!   end or has an enabled edge.
//!
//! Then from every reachable state of the product the target (every
//! vehicle that can end alone at its end) is reachable: the vehicles that
//! hold something give it back one after the other (H2; the others stand
//! still, so the counts only change by the mover's steps and stay within
//! the range H2 was checked for), then, nothing held, each vehicle that can
//! end runs alone to an end holding nothing (H3). And no state is dead
//! unless every vehicle has ended: a vehicle that holds something has an
//! enabled edge (H2), and with nothing held the counts are the initial
//! ones, those of H3. That is the interleaving product's *free* verdict,
//! without its product.

use super::lts::{lab_action, lab_blocked};
use super::product::Effect;
use super::quotient::Quotient;

/// Most count combinations enumerated in one class (H2) before giving up.
const MAX_COMBINATIONS: usize = 4096;

/// True when H1-H3 hold for the vehicles `quots` of a group with the
/// group's `effects`, `init` counts of its supervisor places, `urgent`
/// (per vehicle and effect: a gated start that fires as soon as allowed)
/// and `can_end` (per vehicle: it can end alone): the group is then free.
pub(super) fn prove(
    quots: &[&Quotient],
    effects: &[Effect],
    init: &[u32],
    urgent: &[&[bool]],
    can_end: &[bool],
) -> bool {
    quots
        .iter()
        .enumerate()
        .all(|(v, q)| Vehicle::new(q, effects, init, urgent[v]).is_some_and(|x| x.check(can_end[v])))
}

/// One vehicle's graph with its holdings.
struct Vehicle<'a> {
    q: &'a Quotient,
    effects: &'a [Effect],
    init: &'a [u32],
    urgent: &'a [bool],
    /// Per class: its holding, or `None` when the class is unreachable or
    /// holds more than a place's initial count (never reached either).
    h: Vec<Option<Vec<u32>>>,
}

impl<'a> Vehicle<'a> {
    /// The holdings (H1), or `None` when they do not exist.
    fn new(q: &'a Quotient, effects: &'a [Effect], init: &'a [u32], urgent: &'a [bool]) -> Option<Vehicle<'a>> {
        let ns = init.len();
        let mut h: Vec<Option<Vec<i64>>> = vec![None; q.n];
        let start = *q.block.first()?;
        h[start as usize] = Some(vec![0; ns]);
        let mut stack = vec![start];
        while let Some(c) = stack.pop() {
            let hc = h[c as usize].clone()?;
            for &(label, to) in q.out(c) {
                let mut next = hc.clone();
                if let Some(a) = lab_action(label) {
                    let e = effects.get(a as usize)?;
                    if !e.take_back.is_empty() {
                        return None;
                    }
                    for &(s, w) in &e.consume {
                        *next.get_mut(s)? += i64::from(w);
                    }
                    for &(s, w) in &e.produce {
                        *next.get_mut(s)? -= i64::from(w);
                    }
                }
                match &h[to as usize] {
                    Some(old) if *old != next => return None,
                    Some(_) => {}
                    None => {
                        if next.iter().any(|&x| x < 0) {
                            return None;
                        }
                        h[to as usize] = Some(next);
                        stack.push(to);
                    }
                }
            }
        }
        // A holding above a place's initial count is never reached.
        let h = h
            .into_iter()
            .map(|x| {
                let x = x?;
                let fits = x.iter().zip(init).all(|(&n, &i)| n <= i64::from(i));
                fits.then(|| x.into_iter().map(|n| n as u32).collect())
            })
            .collect();
        Some(Vehicle { q, effects, init, urgent, h })
    }

    fn allowed(&self, counts: &[u32], a: u32) -> bool {
        self.effects[a as usize].consume.iter().all(|&(s, w)| counts[s] >= w)
    }

    /// The classes that the edges out of `c` enabled under `counts` lead
    /// to (the product's rule, `Product::successors` without settling).
    fn enabled(&self, c: u32, counts: &[u32]) -> impl Iterator<Item = u32> + '_ {
        let gate_allowed = self.q.gates[c as usize].iter().any(|&g| self.urgent[g as usize] && self.allowed(counts, g));
        let counts = counts.to_vec();
        self.q.out(c).iter().filter_map(move |&(label, to)| {
            let ok =
                !(lab_blocked(label) && gate_allowed) && lab_action(label).is_none_or(|a| self.allowed(&counts, a));
            // An edge to a class never reached cannot be enabled (H1).
            (ok && self.h[to as usize].is_some()).then_some(to)
        })
    }

    /// Every count vector that the product may show in class `c` as far as
    /// the edges out of `c` can tell: per place they consume from, 0 and
    /// each weight they need, up to initial − h(c); `None` beyond
    /// [`MAX_COMBINATIONS`].
    fn count_choices(&self, c: u32, hc: &[u32]) -> Option<Vec<Vec<u32>>> {
        let mut needs: Vec<(usize, u32)> = Vec::new();
        let gates = self.q.gates[c as usize].iter().copied();
        let actions = self.q.out(c).iter().filter_map(|&(l, _)| lab_action(l));
        for a in gates.chain(actions) {
            needs.extend(self.effects[a as usize].consume.iter().copied());
        }
        needs.sort_unstable();
        needs.dedup();
        let mut out = vec![vec![0u32; self.init.len()]];
        let mut places: Vec<usize> = needs.iter().map(|&(s, _)| s).collect();
        places.dedup();
        for s in places {
            let top = self.init[s] - hc[s];
            let mut values: Vec<u32> = vec![0];
            values.extend(needs.iter().filter(|&&(p, w)| p == s && w <= top).map(|&(_, w)| w));
            if out.len() * values.len() > MAX_COMBINATIONS {
                return None;
            }
            out = out
                .into_iter()
                .flat_map(|x| {
                    values.iter().map(move |&n| {
                        let mut y = x.clone();
                        y[s] = n;
                        y
                    })
                })
                .collect();
        }
        Some(out)
    }

    /// H2 and H3.
    fn check(&self, can_end: bool) -> bool {
        let n = self.q.n;
        let holds = |c: usize| self.h[c].as_ref().is_some_and(|x| x.iter().any(|&k| k > 0));
        let free = |c: usize| self.h[c].as_ref().is_some_and(|x| x.iter().all(|&k| k == 0));
        // H2: the attractor of the classes holding nothing.
        let mut inz: Vec<bool> = (0..n).map(free).collect();
        let mut choices: Vec<Option<Vec<Vec<u32>>>> = vec![None; n];
        for c in (0..n).filter(|&c| holds(c)) {
            match self.count_choices(c as u32, self.h[c].as_deref().unwrap_or(&[])) {
                Some(x) => choices[c] = Some(x),
                None => return false,
            }
        }
        loop {
            let mut changed = false;
            for c in 0..n {
                if !holds(c) || inz[c] {
                    continue;
                }
                let every =
                    choices[c].iter().flatten().all(|counts| self.enabled(c as u32, counts).any(|to| inz[to as usize]));
                if every {
                    inz[c] = true;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        if (0..n).any(|c| holds(c) && !inz[c]) {
            return false;
        }
        // H3: alone, counts initial − h.
        let alone = |c: usize| -> Vec<u32> {
            let hc = self.h[c].as_deref().unwrap_or(&[]);
            self.init.iter().zip(hc).map(|(&i, &k)| i - k).collect()
        };
        if !can_end {
            return (0..n)
                .filter(|&c| free(c) && !self.q.fin[c])
                .all(|c| self.enabled(c as u32, &alone(c)).next().is_some());
        }
        let mut pred: Vec<Vec<u32>> = vec![Vec::new(); n];
        for c in (0..n).filter(|&c| self.h[c].is_some()) {
            for to in self.enabled(c as u32, &alone(c)) {
                pred[to as usize].push(c as u32);
            }
        }
        let mut co: Vec<bool> = (0..n).map(|c| free(c) && self.q.fin[c]).collect();
        let mut stack: Vec<u32> = (0..n as u32).filter(|&c| co[c as usize]).collect();
        while let Some(c) = stack.pop() {
            for &p in &pred[c as usize] {
                if !std::mem::replace(&mut co[p as usize], true) {
                    stack.push(p);
                }
            }
        }
        (0..n).filter(|&c| free(c)).all(|c| co[c])
    }
}

#[cfg(test)]
mod tests {
    use super::super::lts::lab;
    use super::*;

    /// Effects over two places: 1 takes place 0, 2 takes place 1, 3 gives
    /// both back, 4 gives place 0 back, 5 gives place 1 back.
    fn effects() -> Vec<Effect> {
        let e = |consume: Vec<(usize, u32)>, produce: Vec<(usize, u32)>| Effect { consume, produce, take_back: vec![] };
        vec![
            Effect::default(),
            e(vec![(0, 1)], vec![]),
            e(vec![(1, 1)], vec![]),
            e(vec![], vec![(0, 1), (1, 1)]),
            e(vec![], vec![(0, 1)]),
            e(vec![], vec![(1, 1)]),
        ]
    }

    /// A vehicle in a loop taking `first` then `second` (effects), then
    /// giving both back.
    fn nested(first: u32, second: u32) -> Quotient {
        Quotient::from_edges(&[vec![(lab(first, false), 1)], vec![(lab(second, false), 2)], vec![(lab(3, false), 0)]])
    }

    #[test]
    fn taking_one_mutex_at_a_time_is_proven_free() {
        // Take 0, give it back, take 1, give it back, in a loop.
        let q = Quotient::from_edges(&[
            vec![(lab(1, false), 1)],
            vec![(lab(4, false), 2)],
            vec![(lab(2, false), 3)],
            vec![(lab(5, false), 0)],
        ]);
        let urgent = vec![false; 6];
        assert!(prove(&[&q, &q], &effects(), &[1, 1], &[&urgent, &urgent], &[false, false]));
    }

    #[test]
    fn holding_one_mutex_while_waiting_for_another_is_not_proven() {
        // The classic deadlock: one vehicle takes 0 then 1, the other 1
        // then 0. The holdings exist (H1) but a vehicle holding 0 waits for
        // 1 with nothing else to do (H2 fails).
        let (a, b) = (nested(1, 2), nested(2, 1));
        let urgent = vec![false; 6];
        assert!(!prove(&[&a, &b], &effects(), &[1, 1], &[&urgent, &urgent], &[false, false]));
        // Two tokens of each place would be free, but H2 assumes any
        // count the others may leave (down to 0): the rule stays out, the
        // product decides.
        assert!(!prove(&[&a, &b], &effects(), &[2, 2], &[&urgent, &urgent], &[false, false]));
    }

    #[test]
    fn a_vehicle_that_gives_before_it_takes_has_no_holding() {
        // Effect 4 gives place 0 back first: a negative holding (an order).
        let q = Quotient::from_edges(&[vec![(lab(4, false), 1)], vec![(lab(1, false), 0)]]);
        let urgent = vec![false; 6];
        assert!(!prove(&[&q], &effects(), &[1, 1], &[&urgent], &[false]));
    }
}
