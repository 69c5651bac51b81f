//! Topological validation of a geared kinematic chain (paper section 2) and the
//! turning-pair tree rooted at the frame.
//!
//! Checks, in order, each a distinct [`TopologyError`]: connected; deleting
//! the gear edges leaves a spanning tree; L_ind = j_G; every fundamental
//! circuit has one transfer vertex; planarity; Gruebler-Kutzbach mobility;
//! no locked or over-constrained sub-chain and no fractionated mobility (eq. 1).

use std::collections::VecDeque;

use num_traits::Zero;
use petgraph::graph::{NodeIndex, UnGraph};
use petgraph::visit::EdgeRef;
use rustworkx_core::connectivity::articulation_points;
use rustworkx_core::planar::is_planar;

use crate::error::TopologyError;
use crate::model::circuits::{self, FundamentalCircuit};
use crate::model::train::{Edge, GearPair, Link, LinkId, Revolute, RevoluteId};
use crate::numerics::exact::{Q, QMatrix};
use crate::numerics::modp;

/// The tree left by deleting the gear edges, rooted at the frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tree {
    parent: Vec<Option<(LinkId, RevoluteId)>>,
    depth: Vec<usize>,
    order: Vec<LinkId>,
}

impl Tree {
    /// The parent link and the turning pair to it (None for the frame).
    pub fn parent(&self, l: LinkId) -> Option<(LinkId, RevoluteId)> {
        self.parent[l.index()]
    }
    /// Depth below the frame.
    pub fn depth(&self, l: LinkId) -> usize {
        self.depth[l.index()]
    }
    /// Links in breadth-first order from the frame.
    pub fn order(&self) -> &[LinkId] {
        &self.order
    }
    /// The unique tree path from `a` to `b`: its links (both ends included) and turning pairs.
    pub fn path(&self, a: LinkId, b: LinkId) -> (Vec<LinkId>, Vec<RevoluteId>) {
        let (mut x, mut y) = (a, b);
        let (mut up, mut up_e) = (vec![a], Vec::new());
        let (mut down, mut down_e) = (vec![b], Vec::new());
        while self.depth(x) > self.depth(y) {
            let (p, e) = self.parent(x).expect("deeper link has a parent");
            up_e.push(e);
            up.push(p);
            x = p;
        }
        while self.depth(y) > self.depth(x) {
            let (p, e) = self.parent(y).expect("deeper link has a parent");
            down_e.push(e);
            down.push(p);
            y = p;
        }
        while x != y {
            let (px, ex) = self.parent(x).expect("non-root link has a parent");
            let (py, ey) = self.parent(y).expect("non-root link has a parent");
            up_e.push(ex);
            up.push(px);
            down_e.push(ey);
            down.push(py);
            x = px;
            y = py;
        }
        down.pop(); // the meeting link is already last in `up`
        up.extend(down.into_iter().rev());
        up_e.extend(down_e.into_iter().rev());
        (up, up_e)
    }
    /// The path from the frame to `l` (links and turning pairs), as in eq. (4).
    pub fn path_from_root(&self, l: LinkId) -> (Vec<LinkId>, Vec<RevoluteId>) {
        let (mut v, mut e) = (vec![l], Vec::new());
        let mut x = l;
        while let Some((p, r)) = self.parent(x) {
            v.push(p);
            e.push(r);
            x = p;
        }
        v.reverse();
        e.reverse();
        (v, e)
    }
}

/// What the topology analysis yields.
#[derive(Debug)]
pub(crate) struct Topology {
    pub tree: Tree,
    pub circuits: Vec<FundamentalCircuit>,
    pub dof: usize,
    pub checks: Vec<String>,
}

fn names(links: &[Link], ids: impl IntoIterator<Item = LinkId>) -> Vec<String> {
    ids.into_iter()
        .map(|l| links[l.index()].name.clone())
        .collect()
}

pub(crate) fn analyse(
    links: &[Link],
    frame: LinkId,
    levels: &[String],
    revolutes: &[Revolute],
    gears: &[GearPair],
    graph: &UnGraph<LinkId, Edge>,
    clutches: &[[LinkId; 2]],
) -> Result<Topology, TopologyError> {
    let n = links.len();
    let mut checks = Vec::new();

    // 1. Connected.
    let reach = bfs(graph, frame, |_| true);
    let unreached: Vec<LinkId> = (0..n)
        .map(LinkId::from_index)
        .filter(|l| reach[l.index()].is_none())
        .collect();
    if !unreached.is_empty() {
        return Err(TopologyError::Disconnected {
            links: names(links, unreached),
        });
    }
    checks.push(format!("connected: all {n} links reach the frame"));

    // 2. Deleting gear edges leaves a spanning tree.
    let parent = bfs(graph, frame, |e| matches!(e, Edge::Revolute(_)));
    let orphans: Vec<LinkId> = (0..n)
        .map(LinkId::from_index)
        .filter(|l| parent[l.index()].is_none())
        .collect();
    if !orphans.is_empty() {
        return Err(TopologyError::NoTurningPath {
            links: names(links, orphans),
        });
    }
    let tree = make_tree(&parent, frame);
    if revolutes.len() != n - 1 {
        // A turning pair outside the tree closes a loop: report its links.
        let in_tree: Vec<bool> = {
            let mut v = vec![false; revolutes.len()];
            for p in parent.iter().flatten() {
                if let Some((_, Edge::Revolute(r))) = p {
                    v[r.index()] = true;
                }
            }
            v
        };
        let extra = (0..revolutes.len()).find(|&r| !in_tree[r]).unwrap_or(0);
        let [a, b] = revolutes[extra].links;
        let (path, _) = tree.path(a, b);
        return Err(TopologyError::RevoluteCycle {
            links: names(links, path),
        });
    }
    checks.push(format!(
        "deleting the {} gear edges leaves a spanning tree of {} turning pairs",
        gears.len(),
        revolutes.len()
    ));

    // 3. L_ind = j_G (cycle rank of a connected graph: E - V + 1).
    let independent = revolutes.len() + gears.len() + 1 - n;
    if independent != gears.len() {
        return Err(TopologyError::CircuitCount {
            independent,
            gears: gears.len(),
        });
    }
    checks.push(format!("L_ind = j_G = {independent}"));

    // 4. A transfer vertex for every fundamental circuit.
    let circuits = circuits::fundamental_circuits(links, levels, revolutes, gears, &tree)?;
    checks.push(format!(
        "every fundamental circuit ({}) has one transfer vertex",
        circuits.len()
    ));

    // 5. Gruebler-Kutzbach: F = 3(l - 1) - 2 j_R - j_G (before planarity, so
    // that a chain without mobility is called that, not non-planar).
    let dof = 3 * (n as i64 - 1) - 2 * revolutes.len() as i64 - gears.len() as i64;
    if dof < 1 {
        return Err(TopologyError::NoMobility { dof });
    }

    // 6. Planarity.
    if !is_planar(graph) {
        return Err(TopologyError::NonPlanar {
            links: names(links, kuratowski_links(graph)),
        });
    }
    checks.push("the graph is planar".to_string());
    checks.push(format!(
        "Gruebler-Kutzbach F = 3({n} - 1) - 2*{} - {} = {dof}",
        revolutes.len(),
        gears.len()
    ));

    // 7. Eq. (1): no over-constrained or locked sub-chain, for generic ratios (exact rank).
    generic_mobility(links, frame, revolutes, &circuits)?;
    checks.push(format!("no locked or over-constrained sub-chain: the Willis equations have full generic rank {} and every turning pair moves", gears.len()));

    // 8. No fractionated mobility: every turning pair lies on a circuit, and no
    //    link separates two sub-chains that both contain circuits.
    let mut on_circuit = vec![false; revolutes.len()];
    for c in &circuits {
        let (_, edges) = tree.path(c.gear_i, c.gear_j);
        for e in edges {
            on_circuit[e.index()] = true;
        }
    }
    let mut free: Vec<LinkId> = Vec::new();
    for (r, on) in on_circuit.iter().enumerate() {
        if !on {
            // The subtree beyond this pair turns freely.
            let [a, b] = revolutes[r].links;
            let child = if tree.parent(a).is_some_and(|(_, e)| e.index() == r) {
                a
            } else {
                b
            };
            free.extend(subtree(&tree, child));
        }
    }
    // A shaft joined to the train only by clutches (e.g. a transmission's input
    // shaft) turns freely in the bare train; its gear states tie it down.
    free.retain(|l| !clutches.iter().any(|c| c.contains(l)));
    if !free.is_empty() {
        free.sort();
        free.dedup();
        return Err(TopologyError::FreeLinks {
            links: names(links, free),
        });
    }
    let mut cuts: Vec<NodeIndex> = articulation_points(graph, None).into_iter().collect();
    cuts.sort();
    for cut in cuts {
        let parts = join_clutched(components_without(graph, cut), clutches);
        let geared: Vec<Vec<LinkId>> = parts
            .into_iter()
            .filter(|(_, has_gear)| *has_gear)
            .map(|(p, _)| p)
            .collect();
        if geared.len() >= 2 {
            return Err(TopologyError::Fractionated {
                link: links[cut.index()].name.clone(),
                parts: geared.into_iter().map(|p| names(links, p)).collect(),
            });
        }
    }
    checks.push("no fractionated mobility: every turning pair is on a circuit and no link separates geared sub-chains".to_string());

    Ok(Topology {
        tree,
        circuits,
        dof: dof as usize,
        checks,
    })
}

type Parent = Option<Option<(NodeIndex, Edge)>>;

/// Breadth-first search from `root` over edges passing `keep`; `parent[v]` is
/// `Some(None)` for the root, `Some(Some((p, edge)))` for reached links, `None` otherwise.
/// Most edges for which a Kuratowski subgraph is searched (E planarity tests).
const KURATOWSKI_MAX_EDGES: usize = 2000;

/// The links of a minimal non-planar subgraph of a non-planar `graph` (a
/// subdivision of K5 or K3,3, by Kuratowski): every edge whose deletion
/// leaves the graph non-planar is deleted, one at a time.
fn kuratowski_links(graph: &UnGraph<LinkId, Edge>) -> Vec<LinkId> {
    use petgraph::visit::EdgeRef;
    let edges: Vec<(usize, usize)> = graph
        .edge_references()
        .map(|e| (e.source().index(), e.target().index()))
        .collect();
    if edges.len() > KURATOWSKI_MAX_EDGES {
        return Vec::new();
    }
    let n = graph.node_count();
    let build = |keep: &[bool]| {
        let mut h = UnGraph::<(), ()>::with_capacity(n, edges.len());
        for _ in 0..n {
            h.add_node(());
        }
        for (&(a, b), _) in edges.iter().zip(keep).filter(|(_, k)| **k) {
            h.add_edge(NodeIndex::new(a), NodeIndex::new(b), ());
        }
        h
    };
    let mut keep = vec![true; edges.len()];
    for e in 0..edges.len() {
        keep[e] = false;
        if is_planar(&build(&keep)) {
            keep[e] = true;
        }
    }
    let mut used = vec![false; n];
    for (&(a, b), _) in edges.iter().zip(&keep).filter(|(_, k)| **k) {
        used[a] = true;
        used[b] = true;
    }
    (0..n)
        .filter(|&v| used[v])
        .map(|v| graph[NodeIndex::new(v)])
        .collect()
}

fn bfs(graph: &UnGraph<LinkId, Edge>, root: LinkId, keep: impl Fn(&Edge) -> bool) -> Vec<Parent> {
    let mut parent: Vec<Parent> = vec![None; graph.node_count()];
    let r = NodeIndex::new(root.index());
    parent[r.index()] = Some(None);
    let mut queue = VecDeque::from([r]);
    while let Some(v) = queue.pop_front() {
        let mut edges: Vec<_> = graph.edges(v).filter(|e| keep(e.weight())).collect();
        edges.sort_by_key(|e| e.id());
        for e in edges {
            let w = if e.source() == v {
                e.target()
            } else {
                e.source()
            };
            if parent[w.index()].is_none() {
                parent[w.index()] = Some(Some((v, *e.weight())));
                queue.push_back(w);
            }
        }
    }
    parent
}

fn make_tree(parent: &[Parent], root: LinkId) -> Tree {
    let n = parent.len();
    let mut p = vec![None; n];
    for (v, entry) in parent.iter().enumerate() {
        if let Some(Some((u, Edge::Revolute(r)))) = entry {
            p[v] = Some((LinkId::from_index(u.index()), *r));
        }
    }
    let mut depth = vec![0; n];
    let mut order = vec![root];
    let mut children: Vec<Vec<LinkId>> = vec![Vec::new(); n];
    for (v, pv) in p.iter().enumerate() {
        if let Some((u, _)) = pv {
            children[u.index()].push(LinkId::from_index(v));
        }
    }
    let mut k = 0;
    while k < order.len() {
        let v = order[k];
        for &c in &children[v.index()] {
            depth[c.index()] = depth[v.index()] + 1;
            order.push(c);
        }
        k += 1;
    }
    Tree {
        parent: p,
        depth,
        order,
    }
}

fn subtree(tree: &Tree, top: LinkId) -> Vec<LinkId> {
    tree.order()
        .iter()
        .copied()
        .filter(|&l| {
            let mut x = l;
            loop {
                if x == top {
                    return true;
                }
                match tree.parent(x) {
                    Some((p, _)) => x = p,
                    None => return false,
                }
            }
        })
        .collect()
}

/// Connected components of the graph with `cut` removed, each with whether it
/// holds a gear edge (meshes with `cut` itself included).
/// Merge the parts that a clutch joins: sub-chains coupled only through
/// clutches (a transmission's planetary sets) move independently in the bare
/// train, and the gear states tie them together.
fn join_clutched(
    mut parts: Vec<(Vec<LinkId>, bool)>,
    clutches: &[[LinkId; 2]],
) -> Vec<(Vec<LinkId>, bool)> {
    loop {
        let part_of = |l: LinkId| parts.iter().position(|(p, _)| p.contains(&l));
        let joined = clutches
            .iter()
            .find_map(|&[a, b]| match (part_of(a), part_of(b)) {
                (Some(x), Some(y)) if x != y => Some((x.min(y), x.max(y))),
                _ => None,
            });
        let Some((x, y)) = joined else {
            return parts;
        };
        let (links, gear) = parts.swap_remove(y);
        parts[x].0.extend(links);
        parts[x].1 |= gear;
    }
}

fn components_without(graph: &UnGraph<LinkId, Edge>, cut: NodeIndex) -> Vec<(Vec<LinkId>, bool)> {
    let mut seen = vec![false; graph.node_count()];
    seen[cut.index()] = true;
    let mut out = Vec::new();
    for s in graph.node_indices() {
        if seen[s.index()] {
            continue;
        }
        let mut comp = Vec::new();
        let mut has_gear = false;
        let mut stack = vec![s];
        seen[s.index()] = true;
        while let Some(v) = stack.pop() {
            comp.push(LinkId::from_index(v.index()));
            for e in graph.edges(v) {
                let w = if e.source() == v {
                    e.target()
                } else {
                    e.source()
                };
                // A mesh with the cut link itself counts too: a planet meshing
                // only the fixed ring still moves independently of the rest.
                if matches!(e.weight(), Edge::Gear(_)) {
                    has_gear = true;
                }
                if w == cut {
                    continue;
                }
                if !seen[w.index()] {
                    seen[w.index()] = true;
                    stack.push(w);
                }
            }
        }
        comp.sort();
        out.push((comp, has_gear));
    }
    out
}

/// The Willis Jacobian over the coordinates (every link but the frame), exactly.
pub(crate) fn willis_exact(
    n_links: usize,
    frame: LinkId,
    circuits: &[FundamentalCircuit],
    tau: impl Fn(usize) -> Q,
) -> QMatrix {
    let col = |l: LinkId| -> Option<usize> {
        match l.index().cmp(&frame.index()) {
            std::cmp::Ordering::Less => Some(l.index()),
            std::cmp::Ordering::Equal => None,
            std::cmp::Ordering::Greater => Some(l.index() - 1),
        }
    };
    circuits
        .iter()
        .enumerate()
        .map(|(m, c)| {
            let t = tau(m);
            let mut row = vec![Q::zero(); n_links - 1];
            // eq. (2): psi_m = w_i - tau w_j + (tau - 1) w_k
            for (l, v) in [c.gear_i, c.gear_j, c.carrier]
                .into_iter()
                .zip(crate::model::equations::willis_row_exact(&t))
            {
                if let Some(k) = col(l) {
                    row[k] += v;
                }
            }
            row
        })
        .collect()
}

fn generic_mobility(
    links: &[Link],
    frame: LinkId,
    revolutes: &[Revolute],
    circuits: &[FundamentalCircuit],
) -> Result<(), TopologyError> {
    let n = links.len();
    let cols = n - 1;
    let col = |l: LinkId| {
        (l != frame).then(|| {
            if l.index() < frame.index() {
                l.index()
            } else {
                l.index() - 1
            }
        })
    };
    // The Willis Jacobian (eq. 2) with generic ratios, over GF(p) (see
    // `modp`): three entries a row, eliminated sparsely.
    let j: Vec<modp::SparseRow> = circuits
        .iter()
        .enumerate()
        .map(|(m, c)| {
            let t = modp::generic(m as u64);
            let mut row: modp::SparseRow = Vec::with_capacity(3);
            for (l, v) in [
                (c.gear_i, 1),
                (c.gear_j, modp::neg(t)),
                (c.carrier, modp::sub(t, 1)),
            ] {
                if let Some(k) = col(l) {
                    match row.iter_mut().find(|e| e.0 == k) {
                        Some(e) => e.1 = modp::add(e.1, v),
                        None => row.push((k, v)),
                    }
                }
            }
            row.retain(|e| e.1 != 0);
            row
        })
        .collect();
    // Two generic null vectors, not a basis: a train with thousands of
    // degrees of freedom would need one dense vector per freedom (quadratic
    // time and memory); the questions below (is a coordinate zero, do two
    // coincide, on the whole null space) a generic vector answers alike.
    const PROBES: usize = 2;
    let (null, rank) = modp::null_combinations(&j, cols, PROBES, 1 << 40);
    if rank < circuits.len() {
        // Rows with weight in a left null vector are the dependent ones: the
        // null space of the transpose, eliminated sparsely too.
        let mut jt: Vec<modp::SparseRow> = vec![Vec::new(); cols];
        for (m, row) in j.iter().enumerate() {
            for &(c, v) in row {
                jt[c].push((m, v));
            }
        }
        let dependent = modp::support(
            &modp::null_combinations(&jt, circuits.len(), PROBES, 1 << 41).0,
            circuits.len(),
        );
        return Err(TopologyError::Redundant {
            pairs: dependent
                .iter()
                .map(|&m| {
                    format!(
                        "#{} ({})",
                        m + 1,
                        names(links, [circuits[m].gear_i, circuits[m].gear_j]).join("-")
                    )
                })
                .collect(),
        });
    }
    let speed = |v: &Vec<u64>, l: LinkId| col(l).map_or(0, |c| v[c]);
    // A turning pair that never moves, for any motion, belongs to a locked sub-chain.
    let mut locked: Vec<LinkId> = Vec::new();
    for r in revolutes {
        let [a, b] = r.links;
        if null.iter().all(|v| speed(v, a) == speed(v, b)) {
            locked.extend([a, b]);
        }
    }
    // A gear pair whose gear turns with its carrier for every motion never
    // meshes (Willis then stops the other gear too): gears and carrier are a
    // locked sub-chain even when no bearing joins two of them directly (a
    // level may join them through other coaxial links).
    for c in circuits {
        if null
            .iter()
            .all(|v| speed(v, c.gear_i) == speed(v, c.carrier))
        {
            locked.extend([c.gear_i, c.gear_j, c.carrier]);
        }
    }
    if !locked.is_empty() {
        locked.sort();
        locked.dedup();
        return Err(TopologyError::Locked {
            links: names(links, locked),
        });
    }
    Ok(())
}
