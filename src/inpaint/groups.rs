//! Groups of items joined by a symmetric relation: the connected components of the graph whose
//! edges are the related pairs (union-find with path halving). Used for the overlapping balls of
//! D (`guided`) and for the cut ends that face each other across a gap (`holes`).

/// The groups of `0..n` joined through `linked` (called once per pair i < j), each in increasing
/// order, the groups in order of their first member.
pub(crate) fn linked_groups(n: usize, linked: impl Fn(usize, usize) -> bool) -> Vec<Vec<usize>> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for i in 0..n {
        for j in i + 1..n {
            if linked(i, j) {
                let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut slot = vec![usize::MAX; n];
    for i in 0..n {
        let r = root(&mut parent, i);
        if slot[r] == usize::MAX {
            slot[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[slot[r]].push(i);
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::linked_groups;

    #[test]
    fn chains_join_and_singletons_stay_alone() {
        // 0-2, 2-4 chain; 1 and 3 alone.
        let g = linked_groups(5, |a, b| (a, b) == (0, 2) || (a, b) == (2, 4));
        assert_eq!(g, vec![vec![0, 2, 4], vec![1], vec![3]]);
        assert!(linked_groups(0, |_, _| true).is_empty());
    }
}
