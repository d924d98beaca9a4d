//! Structural analysis: incidence matrix, P- and T-invariants, siphons and traps.
//!
//! These results hold for every initial marking and are used to *explain*
//! behaviour: a dead marking usually empties a siphon that contains no marked
//! trap; a place covered by a P-invariant is bounded; and so on (seed,
//! Appendix A.3).
//!
//! * Invariants: minimal-support semi-positive solutions of `y·C = 0` (or
//!   `C·x = 0`) by the Farkas / Fourier–Motzkin algorithm with the
//!   Martinez–Silva support pruning.
//! * Minimal siphons and traps: a branch-and-bound enumeration (Cordone,
//!   Ferrarini, Piroddi, 2005) built on the linear-time *largest siphon inside
//!   a set of places*.
//!
//! Both problems are exponential in the worst case; [`Limits`] caps the work
//! and every result says whether it is complete.

use serde::Serialize;

use crate::model::{Net, PlaceId, TransitionId};

/// Work caps for the exponential algorithms.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Limits {
    /// Largest number of intermediate rows in the Farkas algorithm.
    pub max_rows: usize,
    /// Largest number of search nodes in siphon/trap enumeration.
    pub max_nodes: usize,
    /// Stop after this many results.
    pub max_results: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits { max_rows: 20_000, max_nodes: 200_000, max_results: 10_000 }
    }
}

/// The incidence matrix `C = Post - Pre` (places × transitions).
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct IncidenceMatrix {
    places: usize,
    transitions: usize,
    data: Vec<i64>,
}

impl IncidenceMatrix {
    /// Number of rows (places).
    pub fn places(&self) -> usize {
        self.places
    }

    /// Number of columns (transitions).
    pub fn transitions(&self) -> usize {
        self.transitions
    }

    /// `C[p][t]` (0 when out of range).
    pub fn get(&self, p: PlaceId, t: TransitionId) -> i64 {
        if p.index() < self.places && t.index() < self.transitions {
            self.data[p.index() * self.transitions + t.index()]
        } else {
            0
        }
    }

    /// Row of place `p` (empty when out of range).
    pub fn row(&self, p: PlaceId) -> &[i64] {
        let a = p.index() * self.transitions;
        self.data.get(a..a + self.transitions).unwrap_or(&[])
    }
}

/// The incidence matrix of `net`.
pub fn incidence(net: &Net) -> IncidenceMatrix {
    let (np, nt) = (net.place_count(), net.transition_count());
    let mut data = vec![0i64; np * nt];
    for t in net.transition_ids() {
        for &(p, d) in net.delta(t) {
            data[p.index() * nt + t.index()] = d;
        }
    }
    IncidenceMatrix { places: np, transitions: nt, data }
}

/// A semi-positive invariant: its support with positive integer weights.
pub type Invariant<I> = Vec<(I, u64)>;

/// Result of an invariant computation.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Invariants<I> {
    /// Minimal-support invariants, each with coprime weights, sorted.
    pub invariants: Vec<Invariant<I>>,
    /// False when a cap was hit: the list is then a subset (possibly not
    /// minimal) of the invariants.
    pub complete: bool,
}

/// Minimal semi-positive P-invariants (`y ≥ 0`, `y·C = 0`): weighted token
/// sums that no firing changes.
pub fn p_invariants(net: &Net, limits: &Limits) -> Invariants<PlaceId> {
    let c = incidence(net);
    let rows: Vec<Vec<i64>> = (0..c.places).map(|p| c.row(PlaceId(p as u32)).to_vec()).collect();
    let (inv, complete) = farkas(&rows, c.transitions, limits);
    Invariants {
        invariants: inv.into_iter().map(|v| v.into_iter().map(|(i, w)| (PlaceId(i as u32), w)).collect()).collect(),
        complete,
    }
}

/// Minimal semi-positive T-invariants (`x ≥ 0`, `C·x = 0`): firing counts that
/// reproduce a marking.
pub fn t_invariants(net: &Net, limits: &Limits) -> Invariants<TransitionId> {
    let c = incidence(net);
    let rows: Vec<Vec<i64>> =
        (0..c.transitions).map(|t| (0..c.places).map(|p| c.data[p * c.transitions + t]).collect()).collect();
    let (inv, complete) = farkas(&rows, c.places, limits);
    Invariants {
        invariants: inv
            .into_iter()
            .map(|v| v.into_iter().map(|(i, w)| (TransitionId(i as u32), w)).collect())
            .collect(),
        complete,
    }
}

fn gcd(mut a: i64, mut b: i64) -> i64 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// One row `[c | y]` of the Farkas tableau; `support` is the sorted support of `y`.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Row {
    c: Vec<i64>,
    y: Vec<(usize, i64)>,
}

impl Row {
    fn normalize(&mut self) {
        let g = self.c.iter().chain(self.y.iter().map(|(_, v)| v)).fold(0i64, |g, &x| gcd(g, x));
        if g > 1 {
            self.c.iter_mut().for_each(|x| *x /= g);
            self.y.iter_mut().for_each(|(_, x)| *x /= g);
        }
    }

    fn support_subset(&self, other: &Row) -> bool {
        // Both supports sorted by index.
        let mut it = other.y.iter().map(|&(i, _)| i);
        'outer: for &(i, _) in &self.y {
            for j in it.by_ref() {
                if j == i {
                    continue 'outer;
                }
                if j > i {
                    return false;
                }
            }
            return false;
        }
        true
    }
}

/// `a·x + b·y` for sparse sorted vectors, with overflow check.
fn combine_sparse(a: i64, x: &[(usize, i64)], b: i64, y: &[(usize, i64)]) -> Option<Vec<(usize, i64)>> {
    let mut out = Vec::with_capacity(x.len() + y.len());
    let (mut i, mut j) = (0, 0);
    while i < x.len() || j < y.len() {
        let (k, v) = match (x.get(i), y.get(j)) {
            (Some(&(ki, vi)), Some(&(kj, vj))) if ki == kj => {
                i += 1;
                j += 1;
                (ki, a.checked_mul(vi)?.checked_add(b.checked_mul(vj)?)?)
            }
            (Some(&(ki, vi)), Some(&(kj, _))) if ki < kj => {
                i += 1;
                (ki, a.checked_mul(vi)?)
            }
            (Some(&(ki, vi)), None) => {
                i += 1;
                (ki, a.checked_mul(vi)?)
            }
            (_, Some(&(kj, vj))) => {
                j += 1;
                (kj, b.checked_mul(vj)?)
            }
            (None, None) => break,
        };
        if v != 0 {
            out.push((k, v));
        }
    }
    Some(out)
}

/// Farkas algorithm on `rows` (one per variable, `cols` constraints each).
/// Returns minimal-support semi-positive solutions of `Σ y_i·rows[i] = 0`.
fn farkas(rows: &[Vec<i64>], cols: usize, limits: &Limits) -> (Vec<Vec<(usize, u64)>>, bool) {
    let mut tab: Vec<Row> = rows.iter().enumerate().map(|(i, r)| Row { c: r.clone(), y: vec![(i, 1)] }).collect();
    let mut done = vec![false; cols];
    let mut complete = true;
    for _ in 0..cols {
        // Eliminate the column that creates the fewest new rows.
        let mut best: Option<(usize, usize)> = None;
        for (j, _) in done.iter().enumerate().filter(|(_, &d)| !d) {
            let pos = tab.iter().filter(|r| r.c[j] > 0).count();
            let neg = tab.iter().filter(|r| r.c[j] < 0).count();
            let cost = pos * neg;
            let removed = pos + neg;
            let score = cost.saturating_sub(removed);
            if best.is_none_or(|(_, s)| score < s) {
                best = Some((j, score));
            }
        }
        let Some((j, _)) = best else { break };
        done[j] = true;
        let (pos, rest): (Vec<Row>, Vec<Row>) = tab.into_iter().partition(|r| r.c[j] > 0);
        let (neg, mut next): (Vec<Row>, Vec<Row>) = rest.into_iter().partition(|r| r.c[j] < 0);
        'pairs: for p in &pos {
            for n in &neg {
                let (a, b) = (-n.c[j], p.c[j]);
                let c: Option<Vec<i64>> =
                    p.c.iter().zip(&n.c).map(|(&x, &y)| a.checked_mul(x)?.checked_add(b.checked_mul(y)?)).collect();
                let (Some(c), Some(y)) = (c, combine_sparse(a, &p.y, b, &n.y)) else {
                    // Coefficients too large for i64: give up on this combination.
                    complete = false;
                    continue;
                };
                let mut row = Row { c, y };
                row.normalize();
                // Martinez–Silva: drop rows whose support contains another's.
                if next.iter().any(|o| o.support_subset(&row) && (o.y.len() < row.y.len() || *o == row)) {
                    continue;
                }
                next.retain(|o| !(row.support_subset(o) && row.y.len() < o.y.len()));
                next.push(row);
                if next.len() > limits.max_rows {
                    complete = false;
                    break 'pairs;
                }
            }
        }
        tab = next;
        if !complete {
            break;
        }
    }
    // Keep solved rows (c = 0) with minimal supports.
    let mut sols: Vec<Row> = tab.into_iter().filter(|r| r.c.iter().all(|&x| x == 0)).collect();
    sols.sort_by(|a, b| a.y.len().cmp(&b.y.len()).then_with(|| a.y.cmp(&b.y)));
    let mut kept: Vec<Row> = Vec::new();
    for r in sols {
        if !kept.iter().any(|k| k.support_subset(&r)) {
            kept.push(r);
        }
    }
    let mut out: Vec<Vec<(usize, u64)>> =
        kept.into_iter().map(|r| r.y.into_iter().map(|(i, v)| (i, v.unsigned_abs())).collect()).collect();
    out.sort();
    (out, complete)
}

/// Sets of places found by an enumeration.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct PlaceSets {
    /// Each set sorted by place; sets sorted.
    pub sets: Vec<Vec<PlaceId>>,
    /// False when a cap was hit and some sets may be missing.
    pub complete: bool,
}

/// Orientation of the flow relation: siphons use it as is, traps reversed.
struct Flow<'n> {
    net: &'n Net,
    reversed: bool,
}

impl Flow<'_> {
    /// Transitions that put tokens into p (•p; p• for traps).
    fn feeders(&self, p: PlaceId) -> &[TransitionId] {
        if self.reversed {
            self.net.consumers(p)
        } else {
            self.net.producers(p)
        }
    }

    /// Transitions that take tokens from p (p•; •p for traps).
    fn drainers(&self, p: PlaceId) -> &[TransitionId] {
        if self.reversed {
            self.net.producers(p)
        } else {
            self.net.consumers(p)
        }
    }

    fn inputs(&self, t: TransitionId) -> &[(PlaceId, u32)] {
        if self.reversed {
            self.net.post(t)
        } else {
            self.net.pre(t)
        }
    }

    fn outputs(&self, t: TransitionId) -> &[(PlaceId, u32)] {
        if self.reversed {
            self.net.pre(t)
        } else {
            self.net.post(t)
        }
    }

    /// True when `set` (a membership vector) is a siphon of the oriented net.
    fn is_siphon(&self, set: &[bool]) -> bool {
        set.iter().enumerate().filter(|(_, &b)| b).all(|(p, _)| {
            self.feeders(PlaceId(p as u32)).iter().all(|&t| self.inputs(t).iter().any(|&(q, _)| set[q.index()]))
        })
    }

    /// Largest siphon contained in `set` (in place): repeatedly drops places
    /// fed by a transition with no input in the set. Linear in the arcs.
    fn max_siphon(&self, set: &mut [bool]) {
        let nt = self.net.transition_count();
        let mut cnt = vec![0u32; nt];
        for t in self.net.transition_ids() {
            cnt[t.index()] = self.inputs(t).iter().filter(|&&(q, _)| set[q.index()]).count() as u32;
        }
        let mut queue = Vec::new();
        for t in self.net.transition_ids() {
            if cnt[t.index()] == 0 {
                for &(q, _) in self.outputs(t) {
                    if set[q.index()] {
                        set[q.index()] = false;
                        queue.push(q);
                    }
                }
            }
        }
        while let Some(p) = queue.pop() {
            for &t in self.drainers(p) {
                cnt[t.index()] -= 1;
                if cnt[t.index()] == 0 {
                    for &(q, _) in self.outputs(t) {
                        if set[q.index()] {
                            set[q.index()] = false;
                            queue.push(q);
                        }
                    }
                }
            }
        }
    }

    /// The minimal siphons inside `allowed` that contain a place of
    /// `required_any` (any, when it is empty).
    fn minimal_siphons(&self, allowed: Vec<bool>, required_any: &[PlaceId], limits: &Limits) -> PlaceSets {
        let np = self.net.place_count();
        let mut sets = Vec::new();
        let mut nodes = 0usize;
        let mut complete = true;
        // Regions: (allowed, required). With required places, region i
        // holds the siphons that contain the i-th one and none before it.
        let mut stack: Vec<(Vec<bool>, Vec<bool>)> = Vec::new();
        if required_any.is_empty() {
            stack.push((allowed, vec![false; np]));
        } else {
            let mut a = allowed;
            for r in required_any.iter().filter(|r| r.index() < np) {
                if !a[r.index()] {
                    continue;
                }
                let mut req = vec![false; np];
                req[r.index()] = true;
                stack.push((a.clone(), req));
                a[r.index()] = false;
            }
        }
        while let Some((allowed, required)) = stack.pop() {
            nodes += 1;
            if nodes > limits.max_nodes || sets.len() >= limits.max_results {
                complete = false;
                break;
            }
            let mut s = allowed.clone();
            self.max_siphon(&mut s);
            if !contains(&s, &required) || !s.iter().any(|&b| b) {
                continue;
            }
            // Shrink to a siphon minimal among those containing `required`:
            // drop each place in turn with the places that then lose their
            // last fed input (the largest siphon within the rest, computed
            // from the counts of `s`), and put them back if that loses a
            // required place or everything.
            let mut cnt = self.in_counts(&s);
            let mut size = s.iter().filter(|&&b| b).count();
            let mut removed = Vec::new();
            for p in 0..np {
                if !s[p] || required[p] {
                    continue;
                }
                self.remove_cascade(&mut s, &mut cnt, p, &mut removed);
                if removed.len() == size || removed.iter().any(|&q| required[q]) {
                    self.restore(&mut s, &mut cnt, &removed);
                } else {
                    size -= removed.len();
                }
            }
            if self.is_globally_minimal(&mut s, &mut cnt, size) {
                sets.push(members(&s));
            }
            // Partition the rest of the region: siphons that miss the i-th free
            // place of s but contain the free places before it.
            let free: Vec<usize> = (0..np).filter(|&p| s[p] && !required[p]).collect();
            let mut req = required.clone();
            for &p in &free {
                let mut a = allowed.clone();
                a[p] = false;
                stack.push((a, req.clone()));
                req[p] = true;
            }
        }
        sets.sort();
        PlaceSets { sets, complete }
    }

    /// A non-empty siphon is minimal iff removing any one place leaves no
    /// siphon. `s` (of `size` places, input counts `cnt`) is left as given.
    fn is_globally_minimal(&self, s: &mut [bool], cnt: &mut [u32], size: usize) -> bool {
        let mut removed = Vec::new();
        (0..s.len()).all(|p| {
            if !s[p] {
                return true;
            }
            self.remove_cascade(s, cnt, p, &mut removed);
            let empty = removed.len() == size;
            self.restore(s, cnt, &removed);
            empty
        })
    }

    /// The number of inputs of each transition in `set`.
    fn in_counts(&self, set: &[bool]) -> Vec<u32> {
        self.net
            .transition_ids()
            .map(|t| self.inputs(t).iter().filter(|&&(q, _)| set[q.index()]).count() as u32)
            .collect()
    }

    /// Removes `p` from the siphon `set` (input counts `cnt`) and then every
    /// place fed by a transition left without input in the set: the largest
    /// siphon within `set` minus `p`, as [`Self::max_siphon`] computes it,
    /// in time proportional to what is removed. The removed places are in
    /// `removed`, for [`Self::restore`].
    fn remove_cascade(&self, set: &mut [bool], cnt: &mut [u32], p: usize, removed: &mut Vec<usize>) {
        removed.clear();
        set[p] = false;
        removed.push(p);
        let mut next = 0;
        while next < removed.len() {
            let q = removed[next];
            next += 1;
            for &t in self.drainers(PlaceId(q as u32)) {
                cnt[t.index()] -= 1;
                if cnt[t.index()] == 0 {
                    for &(r, _) in self.outputs(t) {
                        if set[r.index()] {
                            set[r.index()] = false;
                            removed.push(r.index());
                        }
                    }
                }
            }
        }
    }

    /// Undoes [`Self::remove_cascade`].
    fn restore(&self, set: &mut [bool], cnt: &mut [u32], removed: &[usize]) {
        for &q in removed {
            set[q] = true;
            for &t in self.drainers(PlaceId(q as u32)) {
                cnt[t.index()] += 1;
            }
        }
    }
}

fn contains(set: &[bool], sub: &[bool]) -> bool {
    set.iter().zip(sub).all(|(&a, &b)| a || !b)
}

fn members(set: &[bool]) -> Vec<PlaceId> {
    (0..set.len()).filter(|&p| set[p]).map(|p| PlaceId(p as u32)).collect()
}

fn membership(net: &Net, places: &[PlaceId]) -> Vec<bool> {
    let mut v = vec![false; net.place_count()];
    for p in places {
        if let Some(x) = v.get_mut(p.index()) {
            *x = true;
        }
    }
    v
}

/// True when `places` is a siphon: every transition that puts a token into the
/// set also takes one from it (•S ⊆ S•). Once empty, a siphon stays empty.
pub fn is_siphon(net: &Net, places: &[PlaceId]) -> bool {
    Flow { net, reversed: false }.is_siphon(&membership(net, places))
}

/// True when `places` is a trap (S• ⊆ •S). Once marked, a trap stays marked.
pub fn is_trap(net: &Net, places: &[PlaceId]) -> bool {
    Flow { net, reversed: true }.is_siphon(&membership(net, places))
}

/// The largest siphon contained in `places` (possibly empty).
pub fn max_siphon_within(net: &Net, places: &[PlaceId]) -> Vec<PlaceId> {
    let mut s = membership(net, places);
    Flow { net, reversed: false }.max_siphon(&mut s);
    members(&s)
}

/// The largest trap contained in `places` (possibly empty).
pub fn max_trap_within(net: &Net, places: &[PlaceId]) -> Vec<PlaceId> {
    let mut s = membership(net, places);
    Flow { net, reversed: true }.max_siphon(&mut s);
    members(&s)
}

/// All minimal non-empty siphons (capped by `limits`).
pub fn minimal_siphons(net: &Net, limits: &Limits) -> PlaceSets {
    Flow { net, reversed: false }.minimal_siphons(vec![true; net.place_count()], &[], limits)
}

/// The minimal non-empty siphons whose places are all in `allowed` and that
/// contain a place of `required_any` (every one inside `allowed` when it is
/// empty), capped by `limits`: the search of [`minimal_siphons`] started
/// from these regions. Places out of range are ignored.
///
/// A deadlock empties a siphon: with `allowed` the empty places of a dead
/// marking and `required_any` the supervisor places, these are the siphons
/// that a supervisor helped to empty.
pub fn minimal_siphons_within(net: &Net, allowed: &[PlaceId], required_any: &[PlaceId], limits: &Limits) -> PlaceSets {
    Flow { net, reversed: false }.minimal_siphons(membership(net, allowed), required_any, limits)
}

/// All minimal non-empty traps (capped by `limits`).
pub fn minimal_traps(net: &Net, limits: &Limits) -> PlaceSets {
    Flow { net, reversed: true }.minimal_siphons(vec![true; net.place_count()], &[], limits)
}
