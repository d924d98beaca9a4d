//! Graph algorithms on implicit graphs: nodes `0..n`, successors given by a
//! function, so that a state space, a reduced transition system or a
//! subgraph of either needs no copy.

/// The strongly connected components of the graph on nodes `0..n` whose
/// successors of `v` are what `succ(v, out)` pushes into `out` (given
/// empty; successors `>= n` are ignored), by Tarjan's algorithm without
/// recursion (millions of nodes never overflow a stack).
///
/// Calls `emit` with each component in reverse topological order: a
/// component comes after every component it reaches. Roots are tried from
/// node 0 upward and successors in the order given, so the order of the
/// components is deterministic. Memory: a few words per node, and the
/// successors of the nodes on the current path.
pub fn tarjan(n: usize, mut succ: impl FnMut(u32, &mut Vec<u32>), mut emit: impl FnMut(&[u32])) {
    const UNSEEN: u32 = u32::MAX;
    let mut index = vec![UNSEEN; n];
    let mut low = vec![0u32; n];
    let mut on_stack = vec![false; n];
    let mut stack: Vec<u32> = Vec::new();
    let mut component: Vec<u32> = Vec::new();
    let mut buf: Vec<u32> = Vec::new();
    // The successors of every open node, one after another; a frame is
    // (node, next successor position, where its successors start).
    let mut succs: Vec<u32> = Vec::new();
    let mut frames: Vec<(u32, usize, usize)> = Vec::new();
    let mut counter = 0u32;
    let mut open = |v: u32,
                    index: &mut [u32],
                    low: &mut [u32],
                    on_stack: &mut [bool],
                    stack: &mut Vec<u32>,
                    succs: &mut Vec<u32>,
                    frames: &mut Vec<(u32, usize, usize)>| {
        index[v as usize] = counter;
        low[v as usize] = counter;
        counter += 1;
        stack.push(v);
        on_stack[v as usize] = true;
        buf.clear();
        succ(v, &mut buf);
        let start = succs.len();
        succs.extend(buf.iter().copied().filter(|&w| (w as usize) < n));
        frames.push((v, start, start));
    };
    for root in 0..n as u32 {
        if index[root as usize] != UNSEEN {
            continue;
        }
        open(root, &mut index, &mut low, &mut on_stack, &mut stack, &mut succs, &mut frames);
        while let Some(&mut (v, ref mut next, start)) = frames.last_mut() {
            if *next < succs.len() {
                let w = succs[*next];
                *next += 1;
                if index[w as usize] == UNSEEN {
                    open(w, &mut index, &mut low, &mut on_stack, &mut stack, &mut succs, &mut frames);
                } else if on_stack[w as usize] {
                    low[v as usize] = low[v as usize].min(index[w as usize]);
                }
                continue;
            }
            frames.pop();
            succs.truncate(start);
            if let Some(&(parent, ..)) = frames.last() {
                low[parent as usize] = low[parent as usize].min(low[v as usize]);
            }
            if low[v as usize] == index[v as usize] {
                component.clear();
                while let Some(w) = stack.pop() {
                    on_stack[w as usize] = false;
                    component.push(w);
                    if w == v {
                        break;
                    }
                }
                emit(&component);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sccs(n: usize, edges: &[(u32, u32)]) -> Vec<Vec<u32>> {
        let mut out = Vec::new();
        tarjan(
            n,
            |v, s| s.extend(edges.iter().filter(|e| e.0 == v).map(|e| e.1)),
            |c| {
                let mut c = c.to_vec();
                c.sort_unstable();
                out.push(c);
            },
        );
        out
    }

    #[test]
    fn components_come_after_the_components_they_reach() {
        // 0 → {1, 2} cycle → 3 ⇄ 4; 5 alone; an edge out of range ignored.
        let edges = [(0, 1), (1, 2), (2, 1), (2, 3), (3, 4), (4, 3), (5, 9)];
        assert_eq!(sccs(6, &edges), vec![vec![3, 4], vec![1, 2], vec![0], vec![5]]);
    }

    #[test]
    fn a_long_path_needs_no_recursion() {
        let n = 200_000u32;
        let mut count = 0usize;
        let mut first = None;
        tarjan(
            n as usize,
            |v, s| {
                if v + 1 < n {
                    s.push(v + 1);
                }
                if v > 0 && v % 1000 == 0 {
                    s.push(v - 1000);
                }
            },
            |c| {
                count += 1;
                first.get_or_insert(c.len());
            },
        );
        // Nodes 0..=199_000 form one cycle-connected component; the tail
        // 199_001.. is a path of singletons, emitted first.
        assert_eq!(count, 1 + 999);
        assert_eq!(first, Some(1));
    }
}
