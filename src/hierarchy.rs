//! Cluster hierarchy over all elements (§3.2, §4.1), stored in depth-first pre-order so that
//! every subtree is the contiguous row range `[i, end)`: push and pull on the GPU draw one quad or
//! line per range.

use crate::elements::Element;
use glam::DVec3;

/// What a node holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeKind {
    /// A leaf: index of its element.
    Leaf(u32),
    /// A cluster: its two children (the first is always `self + 1`).
    Cluster([u32; 2]),
}

/// One hierarchy node (a row of the intensity tables).
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Area-weighted centroid of the leaves below.
    pub center: DVec3,
    /// Radius of a sphere around `center` enclosing every leaf triangle below.
    pub radius: f64,
    /// Total leaf area below.
    pub area: f64,
    /// One past the last node of this subtree.
    pub end: u32,
    /// Parent node, `u32::MAX` for the root.
    pub parent: u32,
    /// Depth (root 0).
    pub depth: u32,
    /// Leaf or cluster.
    pub kind: NodeKind,
}

/// The element hierarchy.
#[derive(Debug, Clone)]
pub struct Hierarchy {
    /// Nodes in depth-first pre-order; node 0 is the root.
    pub nodes: Vec<Node>,
    /// Node index of each element's leaf.
    pub leaf_of_element: Vec<u32>,
    /// Node indices of all leaves, in row order.
    pub leaves: Vec<u32>,
}

impl Hierarchy {
    /// Builds a binary tree by median splits along the longest axis of the element centroids.
    /// Iterative (an explicit stack in pre-order), so no input can exhaust the call stack.
    pub fn build(elements: &[Element]) -> Self {
        Self::build_grouped(elements, &vec![0; elements.len()])
    }

    /// [`Hierarchy::build`] with every group of elements (`group[e]`, any ids) its own subtree:
    /// the top clusters split between groups (halving the list of groups, in id order), below
    /// them median splits as usual. A moving object is one group (§3.3: "moving objects as own
    /// subtrees"), so every node below the top is static or moves rigidly with one object. With
    /// one group this is exactly [`Hierarchy::build`].
    pub fn build_grouped(elements: &[Element], group: &[u32]) -> Self {
        assert!(!elements.is_empty(), "hierarchy needs at least one element");
        assert_eq!(group.len(), elements.len());
        let mut h = Hierarchy {
            nodes: Vec::with_capacity(2 * elements.len()),
            leaf_of_element: vec![0; elements.len()],
            leaves: Vec::with_capacity(elements.len()),
        };
        let mut idx: Vec<u32> = (0..elements.len() as u32).collect();
        // Groups contiguous in `idx` (stable: one group keeps the element order); `starts` are
        // the positions where a group begins after the first.
        idx.sort_by_key(|&e| group[e as usize]);
        let starts: Vec<usize> = (1..idx.len())
            .filter(|&i| group[idx[i] as usize] != group[idx[i - 1] as usize])
            .collect();
        // A cluster is finished once both subtrees are built: its right child starts where
        // the left subtree ends, and the cluster ends where the right subtree does.
        enum Task {
            Visit {
                range: std::ops::Range<usize>,
                parent: u32,
                depth: u32,
            },
            Finish(u32),
        }
        let mut stack = vec![Task::Visit {
            range: 0..idx.len(),
            parent: u32::MAX,
            depth: 0,
        }];
        while let Some(task) = stack.pop() {
            match task {
                Task::Visit {
                    range,
                    parent,
                    depth,
                } => {
                    // Group boundaries strictly inside the range: split at the middle one.
                    let inside: Vec<usize> = starts
                        .iter()
                        .copied()
                        .filter(|&b| b > range.start && b < range.end)
                        .collect();
                    let forced = inside.get(inside.len() / 2).map(|&b| b - range.start);
                    let slice = &mut idx[range.clone()];
                    if let Some(mid) = h.add_node(elements, slice, parent, depth, forced) {
                        let me = h.nodes.len() as u32 - 1;
                        let split = range.start + mid;
                        stack.push(Task::Finish(me));
                        stack.push(Task::Visit {
                            range: split..range.end,
                            parent: me,
                            depth: depth + 1,
                        });
                        stack.push(Task::Visit {
                            range: range.start..split,
                            parent: me,
                            depth: depth + 1,
                        });
                    }
                }
                Task::Finish(me) => {
                    let l = me + 1;
                    let r = h.nodes[l as usize].end;
                    let end = h.nodes.len() as u32;
                    let node = &mut h.nodes[me as usize];
                    node.kind = NodeKind::Cluster([l, r]);
                    node.end = end;
                }
            }
        }
        h
    }

    /// Appends the node over `idx` (a leaf when it holds one element). For a cluster, orders
    /// `idx` around the median along the longest axis and returns the split position, or
    /// returns `forced` (a group boundary) leaving `idx` as it is.
    fn add_node(
        &mut self,
        els: &[Element],
        idx: &mut [u32],
        parent: u32,
        depth: u32,
        forced: Option<usize>,
    ) -> Option<usize> {
        let me = self.nodes.len() as u32;
        let area: f64 = idx.iter().map(|&i| els[i as usize].area).sum();
        let center = if area > 0.0 {
            idx.iter()
                .map(|&i| els[i as usize].center * els[i as usize].area)
                .sum::<DVec3>()
                / area
        } else {
            idx.iter().map(|&i| els[i as usize].center).sum::<DVec3>() / idx.len() as f64
        };
        let radius = idx
            .iter()
            .flat_map(|&i| els[i as usize].corner_points())
            .map(|c| (c - center).length())
            .fold(0.0, f64::max);
        self.nodes.push(Node {
            center,
            radius,
            area,
            end: me + 1,
            parent,
            depth,
            kind: NodeKind::Leaf(0),
        });
        if idx.len() == 1 {
            self.nodes[me as usize].kind = NodeKind::Leaf(idx[0]);
            self.leaf_of_element[idx[0] as usize] = me;
            self.leaves.push(me);
            return None;
        }
        if forced.is_some() {
            return forced;
        }
        let (lo, hi) = idx.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &i| {
                let c = els[i as usize].center;
                (lo.min(c), hi.max(c))
            },
        );
        // Extents and positions are compared on a grid relative to the node's size, so that
        // the same scene at any scale (rounding differently) builds the same tree.
        let size = (hi - lo).max_element().max(f64::MIN_POSITIVE);
        let quantum = size * 1e-9;
        let q = |v: f64| (v / quantum).round() as i64;
        let ext = (hi - lo).to_array().map(q);
        let axis = if ext[0] >= ext[1] && ext[0] >= ext[2] {
            0
        } else if ext[1] >= ext[2] {
            1
        } else {
            2
        };
        let key = |i: u32| q(els[i as usize].center[axis] - lo[axis]);
        let mid = idx.len() / 2;
        idx.select_nth_unstable_by(mid, |&a, &b| key(a).cmp(&key(b)).then(a.cmp(&b)));
        Some(mid)
    }

    /// Number of nodes (rows).
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True when there are no nodes (never, for a built hierarchy).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Children of a cluster, `None` for a leaf.
    pub fn children(&self, n: u32) -> Option<[u32; 2]> {
        match self.nodes[n as usize].kind {
            NodeKind::Cluster(c) => Some(c),
            NodeKind::Leaf(_) => None,
        }
    }

    /// Element of a leaf node.
    pub fn element(&self, n: u32) -> Option<u32> {
        match self.nodes[n as usize].kind {
            NodeKind::Leaf(e) => Some(e),
            NodeKind::Cluster(_) => None,
        }
    }

    /// Depth of the tree (longest root-to-leaf path, in edges).
    pub fn max_depth(&self) -> u32 {
        self.nodes.iter().map(|n| n.depth).max().unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elements::build_elements;
    use crate::scene::{Material, Scene};

    /// The recursion `Hierarchy::build` replaced; its node order is what the goldens depend on.
    fn recursive(
        h: &mut Hierarchy,
        els: &[Element],
        idx: &mut [u32],
        parent: u32,
        depth: u32,
    ) -> u32 {
        let me = h.nodes.len() as u32;
        let Some(mid) = h.add_node(els, idx, parent, depth, None) else {
            return me;
        };
        let (left, right) = idx.split_at_mut(mid);
        let l = recursive(h, els, left, me, depth + 1);
        let r = recursive(h, els, right, me, depth + 1);
        let end = h.nodes.len() as u32;
        let node = &mut h.nodes[me as usize];
        node.kind = NodeKind::Cluster([l, r]);
        node.end = end;
        me
    }

    #[test]
    fn explicit_stack_builds_the_recursive_tree() {
        let mut s = Scene::empty();
        let m = s.add_material(Material::diffuse("w", 0.5));
        let p = vec![
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.3),
            DVec3::new(0.0, 1.5, 0.0),
            DVec3::new(1.0, 0.5, 2.0),
        ];
        s.add_mesh("q", p, vec![[0, 1, 2], [0, 2, 3], [1, 2, 4], [3, 4, 0]], m);
        for size in [3.0, 0.5, 0.1] {
            s.solver.element_size = size;
            let els = build_elements(&s, &s.solver).unwrap();
            let got = Hierarchy::build(&els);
            let mut want = Hierarchy {
                nodes: Vec::new(),
                leaf_of_element: vec![0; els.len()],
                leaves: Vec::new(),
            };
            let mut idx: Vec<u32> = (0..els.len() as u32).collect();
            recursive(&mut want, &els, &mut idx, u32::MAX, 0);
            assert_eq!(got.nodes, want.nodes, "size {size}");
            assert_eq!(got.leaves, want.leaves);
            assert_eq!(got.leaf_of_element, want.leaf_of_element);
        }
    }

    #[test]
    fn subtrees_are_contiguous_ranges() {
        let mut s = Scene::empty();
        let m = s.add_material(Material::diffuse("w", 0.5));
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        s.add_mesh("q", p, vec![[0, 1, 2], [0, 2, 3]], m);
        s.solver.element_size = 0.2;
        let els = build_elements(&s, &s.solver).unwrap();
        let h = Hierarchy::build(&els);
        assert_eq!(h.leaves.len(), els.len());
        assert_eq!(h.len(), 2 * els.len() - 1);
        for (i, n) in h.nodes.iter().enumerate() {
            // Every node in [i+1, end) has an ancestor chain reaching i; nothing outside does.
            for j in 0..h.len() {
                let mut a = j as u32;
                let mut under = false;
                while a != u32::MAX {
                    if a as usize == i {
                        under = true;
                        break;
                    }
                    a = h.nodes[a as usize].parent;
                }
                assert_eq!(under, (i..n.end as usize).contains(&j));
            }
            if let NodeKind::Cluster([l, r]) = n.kind {
                assert_eq!(l as usize, i + 1);
                assert_eq!(r, h.nodes[l as usize].end);
                assert_eq!(n.end, h.nodes[r as usize].end);
                assert!(
                    (n.area - h.nodes[l as usize].area - h.nodes[r as usize].area).abs() < 1e-12
                );
            }
        }
        for (e, &leaf) in h.leaf_of_element.iter().enumerate() {
            assert_eq!(h.element(leaf), Some(e as u32));
            for c in els[e].corner_points() {
                let mut a = leaf;
                while a != u32::MAX {
                    let n = &h.nodes[a as usize];
                    assert!((c - n.center).length() <= n.radius + 1e-12);
                    a = n.parent;
                }
            }
        }
    }
}
