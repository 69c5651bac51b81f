//! Generated families of gear trains, as spec text, for the benchmarks, the
//! accuracy study and the tests: trains of any size from 3 to 30 links and
//! more, deliberately ill-conditioned ones, and random ones from a seed.
//!
//! * [`gear_pair`]: two wheels on the frame (3 links, the smallest train).
//! * [`planetary_chain`]: k simple planetary sets in series, ring fixed, each
//!   carrier driving the next sun (2 + 2k links, 1 DOF).
//! * [`zigzag_chain`]: the same chain with every other set reversed (carrier
//!   in, sun out), so the speeds stay of order one however long it is: the
//!   large trains of the sparse kinematics (2 + 2k links, 1 DOF).
//! * [`nest`]: planetary stages nested k deep: each planet is the carrier of
//!   the next, so link k rides on k - 1 carriers and its eq. (4) chain has
//!   k - 1 terms (k + 1 links, 1 DOF).
//! * [`random_train`]: simple planetary sets joined at random, Simpson- and
//!   Ravigneaux-like, random tooth counts, inertias over decades (1 DOF).
//! * [`near_locked`]: Fig. 3's reduction gear with tau_1 tau_2 = 1 + eps, which
//!   locks at eps = 0 (w_2 = tau_1 tau_2 / (tau_1 tau_2 - 1) w_4, section 6.1).
//! * [`stationary_planet`]: a planetary set whose planet-ring ratio is 1 + eps,
//!   so the planet barely turns and prescribing its acceleration makes
//!   \[Psi_w\] (eq. 8) nearly singular.
//!
//! Every spec carries an `[analysis]` section: an input link with a speed and
//! an acceleration (also the driving link) and a load torque on an output.

use std::fmt::Write;

/// A small deterministic generator (SplitMix64), so that a seed names a train.
#[derive(Debug, Clone)]
pub struct SplitMix(u64);

impl SplitMix {
    /// From a seed.
    pub fn new(seed: u64) -> Self {
        SplitMix(seed)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform integer in [lo, hi].
    pub fn int(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.next_u64() % (hi - lo + 1) as u64) as i64
    }
    /// Log-uniform in [lo, hi].
    pub fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + self.unit() * (hi.ln() - lo.ln())).exp()
    }
}

fn link(out: &mut String, name: &str, inertia: f64, mass: Option<f64>, copies: u32) {
    let _ = write!(out, "[[links]]\nname = \"{name}\"\ninertia = {inertia:e}\n");
    if let Some(m) = mass {
        let _ = writeln!(out, "mass = {m:e}");
    }
    if copies > 1 {
        let _ = writeln!(out, "copies = {copies}");
    }
    out.push('\n');
}

fn analysis(out: &mut String, input: &str, output: &str) {
    let _ = write!(
        out,
        "[analysis]\nspeeds = {{ \"{input}\" = 157.0 }}\naccelerations = {{ \"{input}\" = 12.5 }}\ntorques = {{ \"{output}\" = -40.0 }}\ndriving = [\"{input}\"]\n"
    );
}

/// Two wheels turning on the frame and meshing: 3 links, 1 DOF.
pub fn gear_pair() -> String {
    let mut s = String::from("name = \"gear pair\"\nframe = \"0\"\n\n");
    link(&mut s, "1", 2.0e-3, None, 1);
    link(&mut s, "2", 5.0e-3, None, 1);
    s.push_str(
        "[[revolutes]]\nlinks = [\"0\", \"1\"]\nlevel = \"a\"\n\n[[revolutes]]\nlinks = [\"0\", \"2\"]\nlevel = \"b\"\n\n\
         [[gears]]\nlinks = [\"1\", \"2\"]\nteeth = [23, 61]\nmesh = \"external\"\nmodule = 2.0e-3\nefficiency = 0.98\n\n",
    );
    analysis(&mut s, "1", "2");
    s
}

/// `k` simple planetary sets in series, ring fixed: sun `s1` in, each carrier
/// `c<i>` drives the next sun, carrier `c<k>` out. 2 + 2k links, 2k gear pairs, 1 DOF.
pub fn planetary_chain(k: usize) -> String {
    let mut s = format!("name = \"planetary chain of {k}\"\nframe = \"case\"\n\n");
    link(&mut s, "s1", 2.0e-4, None, 1);
    for i in 1..=k {
        let sun = if i == 1 {
            "s1".to_string()
        } else {
            format!("c{}", i - 1)
        };
        let zs = 21 + (7 * i as i64) % 13;
        let zp = 17 + (5 * i as i64) % 11;
        let zr = zs + 2 * zp;
        let _ = write!(
            s,
            "[[planetary]]\nname = \"P{i}\"\nsun = \"{sun}\"\nring = \"case\"\ncarrier = \"c{i}\"\n\
             teeth = {{ sun = {zs}, planet = {zp}, ring = {zr} }}\nmodule = 1.5e-3\nefficiency = 0.985\n\n"
        );
        link(&mut s, &format!("c{i}"), 3.5e-3 * i as f64, Some(1.8), 1);
        link(&mut s, &format!("P{i}.planet"), 1.5e-5, Some(0.08), 3);
    }
    analysis(&mut s, "s1", &format!("c{k}"));
    s
}

/// `k` simple planetary sets in series, ring fixed, alternately reducing
/// (sun in, carrier out) and overdriving (carrier in, sun out): the output
/// speed stays of order one for any `k` (a plain chain's underflows past
/// about 500 sets). Links `m0` (input) to `mk` (output); 2 + 2k links.
pub fn zigzag_chain(k: usize) -> String {
    let mut s = format!("name = \"zigzag chain of {k}\"\nframe = \"case\"\n\n");
    link(&mut s, "m0", 2.0e-4, None, 1);
    for i in 1..=k {
        let (prev, next) = (format!("m{}", i - 1), format!("m{i}"));
        let (sun, carrier) = if i % 2 == 1 {
            (&prev, &next)
        } else {
            (&next, &prev)
        };
        let zs = 21 + (7 * i as i64) % 13;
        let zp = 17 + (5 * i as i64) % 11;
        let zr = zs + 2 * zp;
        let _ = write!(
            s,
            "[[planetary]]\nname = \"P{i}\"\nsun = \"{sun}\"\nring = \"case\"\ncarrier = \"{carrier}\"\n\
             teeth = {{ sun = {zs}, planet = {zp}, ring = {zr} }}\nmodule = 1.5e-3\n\n"
        );
        link(&mut s, &next, 3.5e-3, Some(1.8), 1);
        link(&mut s, &format!("P{i}.planet"), 1.5e-5, Some(0.08), 3);
    }
    analysis(&mut s, "m0", &format!("m{k}"));
    s
}

/// `k` planetary sets in series whose rings turn freely (`r1`..): the sun of
/// set i is the carrier of set i - 1 (`m0` the first sun), so each set adds
/// a degree of freedom: 3k + 2 links, k + 1 DOF (a train with thousands of
/// freedoms for the topology checks). With `locked_end` the last set's ring
/// is the frame and a second set `Q` with another ratio joins the same sun
/// and carrier: those two links and the planets can no longer turn (a
/// locked sub-chain at the end of a long mobile one).
pub fn free_ring_chain(k: usize, locked_end: bool) -> String {
    let mut s = format!("name = \"free-ring chain of {k}\"\nframe = \"case\"\n\n");
    link(&mut s, "m0", 2.0e-4, None, 1);
    for i in 1..=k {
        let (prev, next) = (format!("m{}", i - 1), format!("m{i}"));
        let zs = 21 + (7 * i as i64) % 13;
        let zp = 17 + (5 * i as i64) % 11;
        let zr = zs + 2 * zp;
        let ring = if locked_end && i == k {
            "case".to_string()
        } else {
            link(&mut s, &format!("r{i}"), 4.0e-3, None, 1);
            format!("r{i}")
        };
        let _ = write!(
            s,
            "[[planetary]]\nname = \"P{i}\"\nsun = \"{prev}\"\nring = \"{ring}\"\ncarrier = \"{next}\"\n\
             teeth = {{ sun = {zs}, planet = {zp}, ring = {zr} }}\n\n"
        );
        link(&mut s, &next, 3.5e-3, None, 1);
        link(&mut s, &format!("P{i}.planet"), 1.5e-5, None, 3);
    }
    if locked_end {
        let _ = write!(
            s,
            "[[planetary]]\nname = \"Q\"\nsun = \"m{}\"\nring = \"case\"\ncarrier = \"m{k}\"\n\
             teeth = {{ sun = 20, planet = 20, ring = 60 }}\n\n",
            k - 1
        );
        link(&mut s, "Q.planet", 1.5e-5, None, 3);
    }
    s
}

/// Planetary stages nested `links - 1` deep: link 1 turns on the frame, link
/// k on link k - 1 (each at its own level), and gear pair (k - 2, k) meshes
/// across carrier k - 1. `links` links (at least 3), 1 DOF. Links 2 and 3
/// carry a mass (link 3 as two evenly spaced copies, so that its coupling of
/// carriers 1 and 2 cancels); deeper links would couple carriers through
/// angle-dependent terms, which a prepared train does not model, so they
/// carry inertia only.
pub fn nest(links: usize) -> String {
    assert!(links >= 3, "a nest needs at least 3 links");
    let n = links - 1;
    let mut s = format!("name = \"nest of {n}\"\nframe = \"0\"\n\n");
    for k in 1..=n {
        link(
            &mut s,
            &k.to_string(),
            1.0e-3 * (1 + k % 3) as f64,
            (k == 2 || k == 3).then_some(0.2 + 0.05 * k as f64),
            if k == 3 { 2 } else { 1 },
        );
    }
    for k in 1..=n {
        let _ = write!(
            s,
            "[[revolutes]]\nlinks = [\"{}\", \"{k}\"]\nlevel = \"L{k}\"\n\n",
            k - 1
        );
    }
    for k in 2..=n {
        let zi = 20 + (7 * k) % 13;
        let zj = 15 + (5 * k) % 11;
        let _ = write!(
            s,
            "[[gears]]\nlinks = [\"{}\", \"{k}\"]\nteeth = [{zi}, {zj}]\nmesh = \"external\"\nmodule = 1.0e-3\nefficiency = 0.98\n\n",
            k - 2
        );
    }
    analysis(&mut s, "1", &n.to_string());
    s
}

/// `sets` simple planetary sets joined at random (seeded): the first has its
/// ring fixed; each later one makes one new central member (sun, ring or
/// carrier, at random) and takes the other two from the central links so far
/// (the frame included). Random tooth counts; inertias spread over
/// `inertia_decades` decades. 2 + 2 sets links, 1 DOF. Joins that would make
/// the graph non-planar or lock a sub-chain are redrawn (a valid train is
/// found within a few draws; the same seed always gives the same train).
pub fn random_train(seed: u64, sets: usize, inertia_decades: f64) -> String {
    let mut last = String::new();
    for attempt in 0..1000 {
        last = random_draw(
            seed.wrapping_mul(1000).wrapping_add(attempt),
            sets,
            inertia_decades,
        );
        if egt_core::Train::from_str(&last, egt_core::Format::Toml, "random").is_ok() {
            break;
        }
    }
    last
}

fn random_draw(seed: u64, sets: usize, inertia_decades: f64) -> String {
    let mut r = SplitMix::new(seed);
    let mut s = format!("name = \"random train {seed}, {sets} sets\"\nframe = \"case\"\n\n");
    let mut central: Vec<String> = vec!["case".into()];
    let mut created: Vec<String> = Vec::new();
    let spread = 10f64.powf(inertia_decades / 2.0);
    for i in 1..=sets {
        let new = format!("m{i}");
        let (sun, ring, carrier) = if i == 1 {
            ("s0".to_string(), "case".to_string(), new.clone())
        } else {
            let a = r.int(0, central.len() as i64 - 1) as usize;
            let mut b = r.int(0, central.len() as i64 - 2) as usize;
            if b >= a {
                b += 1;
            }
            let (x, y) = (central[a].clone(), central[b].clone());
            match r.int(0, 2) {
                0 => (new.clone(), x, y),
                1 => (x, new.clone(), y),
                _ => (x, y, new.clone()),
            }
        };
        if i == 1 {
            central.push("s0".into());
            created.push("s0".into());
        }
        central.push(new.clone());
        created.push(new);
        let zs = r.int(17, 41);
        let zp = r.int(13, 31);
        let zr = zs + 2 * zp;
        let _ = write!(
            s,
            "[[planetary]]\nname = \"P{i}\"\nsun = \"{sun}\"\nring = \"{ring}\"\ncarrier = \"{carrier}\"\n\
             teeth = {{ sun = {zs}, planet = {zp}, ring = {zr} }}\nmodule = 1.5e-3\nefficiency = 0.985\n\n"
        );
        link(
            &mut s,
            &format!("P{i}.planet"),
            2.0e-5 * r.log_uniform(1.0 / spread, spread),
            Some(0.1 * r.log_uniform(1.0 / spread, spread)),
            3,
        );
    }
    for name in &created {
        link(
            &mut s,
            name,
            4.0e-3 * r.log_uniform(1.0 / spread, spread),
            Some(2.0 * r.log_uniform(1.0 / spread, spread)),
            1,
        );
    }
    let output = created.last().cloned().unwrap_or_default();
    analysis(&mut s, "s0", &output);
    s
}

/// Fig. 3's reduction gear (example 6.1) with ratios tau_1 = -2/3 and
/// tau_2 = (1 + eps) / tau_1: as eps -> 0 the train locks and the condition
/// number of \[Psi_w\] grows like 1 / eps.
pub fn near_locked(eps: f64) -> String {
    let t1 = -2.0 / 3.0;
    let t2 = (1.0 + eps) / t1;
    let mut s = format!("name = \"near-locked Fig. 3, eps = {eps:e}\"\nframe = \"1\"\n\n");
    link(&mut s, "2", 2.0e-3, Some(1.5), 1);
    link(&mut s, "3", 4.0e-5, Some(0.12), 3);
    link(&mut s, "4", 1.2e-3, None, 1);
    let _ = write!(
        s,
        "[[revolutes]]\nlinks = [\"1\", \"2\"]\nlevel = \"a\"\n\n[[revolutes]]\nlinks = [\"2\", \"3\"]\nlevel = \"b\"\n\n\
         [[revolutes]]\nlinks = [\"1\", \"4\"]\nlevel = \"a\"\n\n\
         [[offsets]]\nlevels = [\"a\", \"b\"]\ndistance = 0.05\n\n\
         [[gears]]\nlinks = [\"1\", \"3\"]\nratio = {t1:e}\n\n[[gears]]\nlinks = [\"3\", \"4\"]\nratio = {t2:e}\n\n"
    );
    analysis(&mut s, "4", "2");
    s
}

/// A planetary set (ring fixed) whose planet-ring ratio is 1 + eps, with the
/// planet as the input: the planet's absolute speed is about eps times the
/// carrier's, so \[Psi_w\] (eq. 8) is nearly singular.
pub fn stationary_planet(eps: f64) -> String {
    let mut s = format!("name = \"stationary planet, eps = {eps:e}\"\nframe = \"case\"\n\n");
    link(&mut s, "sun", 2.0e-4, None, 1);
    link(&mut s, "carrier", 3.5e-3, Some(1.8), 1);
    link(&mut s, "planet", 1.5e-5, Some(0.08), 3);
    let ratio = 1.0 + eps;
    let _ = write!(
        s,
        "[[revolutes]]\nlinks = [\"case\", \"sun\"]\nlevel = \"a\"\n\n[[revolutes]]\nlinks = [\"case\", \"carrier\"]\nlevel = \"a\"\n\n\
         [[revolutes]]\nlinks = [\"carrier\", \"planet\"]\nlevel = \"p\"\n\n\
         [[offsets]]\nlevels = [\"a\", \"p\"]\ndistance = 0.04\n\n\
         [[gears]]\nlinks = [\"sun\", \"planet\"]\nratio = -0.7\n\n[[gears]]\nlinks = [\"planet\", \"case\"]\nratio = {ratio:e}\n\n"
    );
    analysis(&mut s, "planet", "carrier");
    s
}
