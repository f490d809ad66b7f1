//! Structural checks of a BVH: what every traversal relies on.

use super::aabb::Aabb;
use super::layout::NONE;
use super::{Bvh, node_box};

/// A tree that breaks an invariant the traversals rely on: the first violation found, in words.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct InvalidTree(pub String);

impl<S: Into<String>> From<S> for InvalidTree {
    fn from(message: S) -> Self {
        InvalidTree(message.into())
    }
}

impl Bvh {
    /// Checks that every primitive is in exactly one leaf, that parent and child links agree, that
    /// every internal box is exactly the union of its children's and every leaf box contains its
    /// primitive's (`primitive_boxes`), and that escape links follow depth-first order (left child
    /// first). Returns the first violation found.
    pub fn validate(&self, primitive_boxes: &[Aabb]) -> Result<(), InvalidTree> {
        let n = self.primitive_count;
        if primitive_boxes.len() != n {
            return Err(format!("{} primitive boxes for {n} primitives", primitive_boxes.len()).into());
        }
        if n == 0 {
            return if self.nodes.is_empty() {
                Ok(())
            } else {
                Err("nodes without primitives".into())
            };
        }
        if self.nodes.len() != 2 * n - 1 {
            return Err(format!("{} nodes for {n} primitives, expected {}", self.nodes.len(), 2 * n - 1).into());
        }
        if self.nodes[0].parent != NONE {
            return Err("the root has a parent".into());
        }
        let mut seen = vec![false; n];
        let mut is_child = vec![false; self.nodes.len()];
        for (i, node) in self.nodes.iter().enumerate() {
            let b = node_box(node);
            if node.is_leaf() {
                let p = node.left as usize;
                if p >= n {
                    return Err(format!("leaf {i} names primitive {p} of {n}").into());
                }
                if std::mem::replace(&mut seen[p], true) {
                    return Err(format!("primitive {p} is in two leaves").into());
                }
                if !b.contains(primitive_boxes[p]) {
                    return Err(format!("leaf {i} does not contain primitive {p}").into());
                }
                continue;
            }
            let mut union = Aabb::EMPTY;
            for child in [node.left, node.right] {
                let c = child as usize;
                if c >= self.nodes.len() || c == 0 {
                    return Err(format!("node {i} has child {child}").into());
                }
                if std::mem::replace(&mut is_child[c], true) {
                    return Err(format!("node {c} has two parents").into());
                }
                if self.nodes[c].parent != i as u32 {
                    return Err(format!("node {c} is a child of {i} but names parent {}", self.nodes[c].parent).into());
                }
                union = union.union(node_box(&self.nodes[c]));
            }
            if union != b {
                return Err(format!("node {i}'s box {b:?} is not the union of its children's {union:?}").into());
            }
        }
        if let Some(p) = seen.iter().position(|&s| !s) {
            return Err(format!("primitive {p} is in no leaf").into());
        }
        if let Some(c) = (1..self.nodes.len()).find(|&c| !is_child[c]) {
            return Err(format!("node {c} is unreachable").into());
        }
        // Depth-first order, left child first; each node's escape is the next node after its subtree.
        let mut order = Vec::with_capacity(self.nodes.len());
        let mut subtree_end = vec![0usize; self.nodes.len()];
        let mut stack = vec![(0u32, false)];
        while let Some((node, done)) = stack.pop() {
            let i = node as usize;
            if done {
                subtree_end[i] = order.len();
                continue;
            }
            order.push(node);
            stack.push((node, true));
            if !self.nodes[i].is_leaf() {
                stack.push((self.nodes[i].right, false));
                stack.push((self.nodes[i].left, false));
            }
        }
        for (i, node) in self.nodes.iter().enumerate() {
            let expected = order.get(subtree_end[i]).copied().unwrap_or(NONE);
            if node.escape != expected {
                return Err(format!("node {i} escapes to {} instead of {expected}", node.escape).into());
            }
        }
        Ok(())
    }
}
