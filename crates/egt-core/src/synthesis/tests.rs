//! Tests of the atlas: egt's checks on every member, partitions, known trains.
//! (The canonical form is tested against brute force in `canon.rs`.)
#![allow(clippy::unwrap_used)]

use super::*;

fn atlas(
    links: usize,
    dof: usize,
    level: GraphLevel,
    part: Option<(usize, usize)>,
) -> Vec<AtlasMember> {
    enumerate(&AtlasRequest {
        links,
        dof,
        level,
        part,
    })
    .unwrap()
}

fn train(adjacency: &str) -> Result<Train> {
    Train::from_str(
        &format!("frame = \"1\"\nadjacency = \"{adjacency}\"\n"),
        Format::Toml,
        "atlas",
    )
}

#[test]
fn every_member_passes_egt_check_and_has_the_requested_dof() {
    for (n, f) in [(3, 1), (4, 1), (5, 1), (5, 2)] {
        for level in [GraphLevel::Rotation, GraphLevel::Displacement] {
            for m in atlas(n, f, level, None) {
                let t = train(&m.adjacency).unwrap();
                assert_eq!(t.dof(), f, "{}", m.adjacency);
                assert_eq!(t.links().len(), n);
                assert_eq!(t.gears().len(), m.gears);
            }
        }
    }
}

#[test]
fn members_are_pairwise_non_isomorphic_and_rotation_sums_displacement() {
    for (n, f) in [(4, 1), (5, 1), (5, 2)] {
        let r = atlas(n, f, GraphLevel::Rotation, None);
        let d = atlas(n, f, GraphLevel::Displacement, None);
        let mut codes: Vec<&str> = d.iter().map(|m| m.code.as_str()).collect();
        codes.sort_unstable();
        codes.dedup();
        assert_eq!(codes.len(), d.len());
        let mut rc: Vec<&str> = r.iter().map(|m| m.code.as_str()).collect();
        rc.sort_unstable();
        rc.dedup();
        assert_eq!(rc.len(), r.len());
        assert_eq!(
            r.iter().map(|m| m.displacement_graphs).sum::<usize>(),
            d.len()
        );
    }
}

#[test]
fn partitions_are_disjoint_and_cover_the_atlas() {
    let whole = atlas(5, 1, GraphLevel::Displacement, None);
    let mut parts: Vec<AtlasMember> = (0..2)
        .flat_map(|p| atlas(5, 1, GraphLevel::Displacement, Some((p, 2))))
        .collect();
    parts.sort_by(|a, b| a.code.cmp(&b.code));
    let mut w = whole.clone();
    w.sort_by(|a, b| a.code.cmp(&b.code));
    assert_eq!(parts, w);
}

#[test]
fn the_simple_planetary_set_is_the_four_link_member_with_sun_and_ring_coaxial() {
    // carrier 4; sun 1 and ring 3 on the main axis a; planet 2 on axis b.
    let mut g = ChainGraph::empty(4);
    g.set(0, 3, Joint::Turning);
    g.set(2, 3, Joint::Turning);
    g.set(1, 3, Joint::Turning);
    g.set(0, 1, Joint::Gear);
    g.set(1, 2, Joint::Gear);
    let levels: Vec<usize> = g
        .pairs(Joint::Turning)
        .iter()
        .map(|&(a, _)| usize::from(a == 1))
        .collect();
    let (code, _) = canonical(&g, Extra::Levels(&levels));
    let hex: String = code.iter().map(|b| format!("{b:02x}")).collect();
    let d = atlas(4, 1, GraphLevel::Displacement, None);
    assert!(d.iter().any(|m| m.code == hex), "{d:?}");
}

#[test]
fn bad_requests_name_the_field() {
    let bad = |links, dof, part| {
        enumerate(&AtlasRequest {
            links,
            dof,
            level: GraphLevel::Rotation,
            part,
        })
        .unwrap_err()
        .to_string()
    };
    assert!(bad(2, 1, None).contains("links"));
    assert!(bad(5, 0, None).contains("dof"));
    assert!(bad(5, 4, None).contains("dof"));
    assert!(bad(5, 1, Some((2, 2))).contains("part"));
}

#[test]
fn differently_seeded_generation_orders_give_the_same_set() {
    // Relabelling each tree at random changes the order in which gear-pair
    // subsets and level partitions are generated; the set of codes must not change.
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed as usize
    };
    for level in [GraphLevel::Rotation, GraphLevel::Displacement] {
        let req = AtlasRequest {
            links: 6,
            dof: 1,
            level,
            part: None,
        };
        for t in trees::trees(6) {
            let codes = |g: &ChainGraph| {
                let mut c: Vec<String> = members_of_tree(g, &req)
                    .into_iter()
                    .map(|m| m.code)
                    .collect();
                c.sort();
                c
            };
            let base = codes(&t);
            for _ in 0..2 {
                let mut perm: Vec<usize> = (0..6).collect();
                for i in (1..6).rev() {
                    perm.swap(i, next() % (i + 1));
                }
                assert_eq!(codes(&t.permuted(&perm)), base);
            }
        }
    }
}
