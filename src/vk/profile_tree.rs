//! GPU scopes as a tree: scopes that nest in a command buffer nest in the tree, and
//! scopes on the same path are added up, so that a node's total is its self time plus
//! its children's totals and the self times of all nodes add up to the GPU time.

use std::fmt::Write as _;

use serde::Serialize;

use super::profiler::ProfileRecord;

/// One path of the scope tree.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ProfileNode {
    pub name: String,
    /// Scopes on this path (0 for the per-stream nodes of a multi-stream tree).
    pub count: usize,
    /// Time inside the scopes, nested scopes included.
    pub total_ms: f64,
    /// `total_ms` less the children's `total_ms`.
    pub self_ms: f64,
    /// The longest single scope on this path.
    pub max_ms: f64,
    /// Longest total first.
    pub children: Vec<ProfileNode>,
}

/// The scopes of a [`ProfileLog`](super::ProfileLog) as a tree. Where records come from
/// more than one stream, each stream is a root and its scopes hang below it (streams
/// may run at once, so their totals overlap in time).
#[derive(Clone, Debug, Default, Serialize)]
pub struct ProfileTree {
    /// The roots' totals added up.
    pub total_ms: f64,
    pub roots: Vec<ProfileNode>,
}

/// Each record's duration less the durations of the records directly nested in it.
pub(crate) fn self_times_ms(records: &[ProfileRecord]) -> Vec<f64> {
    let mut own: Vec<f64> = records.iter().map(|r| r.duration_ms()).collect();
    let mut open: Vec<usize> = Vec::new();
    for (i, r) in records.iter().enumerate() {
        open.truncate(r.depth as usize);
        if let Some(&parent) = open.last().filter(|_| open.len() == r.depth as usize) {
            own[parent] -= r.duration_ms();
        }
        open.push(i);
    }
    own
}

/// The tree while it is being built: nodes in an arena, index 0 the invisible root.
struct Arena {
    nodes: Vec<(ProfileNode, Vec<usize>)>,
}

impl Arena {
    fn child(&mut self, parent: usize, name: &str) -> usize {
        if let Some(&c) = self.nodes[parent]
            .1
            .iter()
            .find(|&&c| self.nodes[c].0.name == name)
        {
            return c;
        }
        let id = self.nodes.len();
        self.nodes.push((
            ProfileNode {
                name: name.to_string(),
                ..Default::default()
            },
            Vec::new(),
        ));
        self.nodes[parent].1.push(id);
        id
    }

    fn build(&self, id: usize) -> ProfileNode {
        let (node, children) = &self.nodes[id];
        let mut children: Vec<ProfileNode> = children.iter().map(|&c| self.build(c)).collect();
        children.sort_by(|a, b| b.total_ms.total_cmp(&a.total_ms));
        ProfileNode {
            children,
            ..node.clone()
        }
    }
}

impl ProfileTree {
    /// Aggregates records by path. Records must be in the order [`ProfileLog`] keeps
    /// them: each command buffer's contiguous, its scopes in the order they began.
    ///
    /// [`ProfileLog`]: super::ProfileLog
    pub fn from_records(records: &[ProfileRecord]) -> Self {
        let own = self_times_ms(records);
        let per_stream = records
            .first()
            .is_some_and(|first| records.iter().any(|r| r.stream != first.stream));
        let mut arena = Arena {
            nodes: vec![(ProfileNode::default(), Vec::new())],
        };
        // Node ids of the open scopes, outermost first.
        let mut open: Vec<usize> = Vec::new();
        for (r, own) in records.iter().zip(own) {
            open.truncate(r.depth as usize);
            let parent = match open.last() {
                Some(&p) => p,
                None if per_stream => arena.child(0, r.stream.name()),
                None => 0,
            };
            let id = arena.child(parent, &r.name);
            let ms = r.duration_ms();
            let node = &mut arena.nodes[id].0;
            node.count += 1;
            node.total_ms += ms;
            node.self_ms += own;
            node.max_ms = node.max_ms.max(ms);
            if per_stream && r.depth == 0 {
                let stream = &mut arena.nodes[parent].0;
                stream.total_ms += ms;
                stream.max_ms = stream.max_ms.max(ms);
            }
            open.push(id);
        }
        let roots = arena.build(0).children;
        Self {
            total_ms: roots.iter().map(|r| r.total_ms).sum(),
            roots,
        }
    }

    /// Every node, depth first, with its depth.
    pub fn walk(&self) -> Vec<(usize, &ProfileNode)> {
        fn visit<'a>(n: &'a ProfileNode, depth: usize, out: &mut Vec<(usize, &'a ProfileNode)>) {
            out.push((depth, n));
            for c in &n.children {
                visit(c, depth + 1, out);
            }
        }
        let mut out = Vec::new();
        for r in &self.roots {
            visit(r, 0, &mut out);
        }
        out
    }

    /// A printable table: one line per path, indented by depth, and a closing line whose
    /// total is the roots' totals and whose self time is every node's self time added up
    /// (the two agree).
    pub fn table(&self) -> String {
        let rows = self.walk();
        let width = rows
            .iter()
            .map(|(d, n)| 2 * d + n.name.len())
            .max()
            .unwrap_or(5)
            .max(5);
        let mut s = format!(
            "{:<width$}  {:>7}  {:>11}  {:>11}  {:>10}  {:>10}\n",
            "scope", "count", "total ms", "self ms", "mean ms", "max ms"
        );
        for (depth, n) in &rows {
            let name = format!("{:indent$}{}", "", n.name, indent = 2 * depth);
            if n.count == 0 {
                let _ = writeln!(
                    s,
                    "{name:<width$}  {:>7}  {:>11.3}  {:>11.3}",
                    "", n.total_ms, n.self_ms
                );
            } else {
                let _ = writeln!(
                    s,
                    "{name:<width$}  {:>7}  {:>11.3}  {:>11.3}  {:>10.4}  {:>10.4}",
                    n.count,
                    n.total_ms,
                    n.self_ms,
                    n.total_ms / n.count as f64,
                    n.max_ms
                );
            }
        }
        let self_sum: f64 = rows.iter().map(|(_, n)| n.self_ms).sum();
        // `+ 0.0` turns an empty tree's −0 into 0 for printing.
        let _ = writeln!(
            s,
            "{:<width$}  {:>7}  {:>11.3}  {:>11.3}",
            "all scopes",
            "",
            self.total_ms + 0.0,
            self_sum + 0.0
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vk::{ScopeInfo, StreamKind};

    fn record(stream: StreamKind, name: &str, depth: u32, start: f64, end: f64) -> ProfileRecord {
        ProfileRecord {
            stream,
            name: name.into(),
            start_ns: start * 1e6,
            end_ns: end * 1e6,
            depth,
            submission: 1,
            info: ScopeInfo::default(),
        }
    }

    fn assert_adds_up(node: &ProfileNode) {
        let children: f64 = node.children.iter().map(|c| c.total_ms).sum();
        assert!(
            (node.self_ms + children - node.total_ms).abs() < 1e-9,
            "{node:?}"
        );
        node.children.iter().for_each(assert_adds_up);
    }

    #[test]
    fn nested_scopes_aggregate_by_path_and_add_up() {
        use StreamKind::Main;
        // Two command buffers: level { split, split, intersect }, then a bare split.
        let records = vec![
            record(Main, "level", 0, 0.0, 10.0),
            record(Main, "split", 1, 0.0, 2.0),
            record(Main, "split", 1, 2.0, 5.0),
            record(Main, "intersect", 1, 5.0, 9.0),
            record(Main, "split", 0, 12.0, 13.0),
        ];
        let tree = ProfileTree::from_records(&records);
        assert_eq!(tree.roots.len(), 2);
        let level = &tree.roots[0];
        assert_eq!((level.name.as_str(), level.count), ("level", 1));
        assert!((level.self_ms - 1.0).abs() < 1e-9);
        let split = level.children.iter().find(|c| c.name == "split").unwrap();
        assert_eq!(split.count, 2);
        assert!((split.total_ms - 5.0).abs() < 1e-9);
        assert!((split.max_ms - 3.0).abs() < 1e-9);
        // The bare split is its own path, not merged with the nested ones.
        assert_eq!(tree.roots[1].name, "split");
        assert!((tree.total_ms - 11.0).abs() < 1e-9);
        tree.roots.iter().for_each(assert_adds_up);
        let self_sum: f64 = tree.walk().iter().map(|(_, n)| n.self_ms).sum();
        assert!((self_sum - tree.total_ms).abs() < 1e-9);
        assert_eq!(tree.table().lines().count(), 1 + 4 + 1, "{}", tree.table());
    }

    #[test]
    fn several_streams_become_roots() {
        let records = vec![
            record(StreamKind::Main, "a", 0, 0.0, 4.0),
            record(StreamKind::Aux0, "b", 0, 1.0, 2.0),
            record(StreamKind::Aux0, "c", 1, 1.0, 1.5),
        ];
        let tree = ProfileTree::from_records(&records);
        let names: Vec<_> = tree.roots.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(names, ["main", "aux0"]);
        assert!((tree.total_ms - 5.0).abs() < 1e-9);
        tree.roots.iter().for_each(assert_adds_up);
        let aux0 = &tree.roots[1];
        assert_eq!(aux0.children[0].children[0].name, "c");
    }

    #[test]
    fn flat_summary_self_times_add_up() {
        let records = vec![
            record(StreamKind::Main, "outer", 0, 0.0, 10.0),
            record(StreamKind::Main, "k", 1, 1.0, 4.0),
            record(StreamKind::Main, "k", 1, 4.0, 6.0),
        ];
        let log = crate::vk::ProfileLog { records };
        let summary = log.summary();
        let self_sum: f64 = summary.iter().map(|k| k.self_ms).sum();
        assert!((self_sum - 10.0).abs() < 1e-9);
        let outer = summary.iter().find(|k| k.name == "outer").unwrap();
        assert!((outer.self_ms - 5.0).abs() < 1e-9);
    }
}
