//! Batch evaluation for screening: one prepared plan, many parameter rows,
//! solved in parallel (rayon, one plan per worker) with the GIL released.
//!
//! Each row is independent. A row that cannot be solved (a zero tooth count, a
//! non-finite value, a singular or ill-conditioned system, a panic) does not
//! stop the batch: its outputs stay 0.0, `ok[row]` is false and the row's
//! error kind and message are reported. No NaN is ever written.
//!
//! The per-row work allocates nothing: buffers belong to the worker's state and
//! the plans of egt-core ([`KinematicsPlan`], [`InverseDynamicsPlan`]) reuse
//! theirs.

use std::panic::{AssertUnwindSafe, catch_unwind};

use egt_core::dynamics::{Extra, InverseDynamicsPlan};
use egt_core::kinematics::{KinematicsPlan, willis_residual};
use egt_core::spec::MeshKind;
use egt_core::{AnalysisError, LinkId, SpecErrorKind, Train};
use numpy::{PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

use crate::convert::{self, mat2, mat2_of, vec1};
use crate::errors::{Result, guard, kind, panic_message, value_error};
use crate::train::TrainCore;

/// Rows handed to a worker at a time (keeps rayon's splitting overhead small).
const MIN_ROWS_PER_TASK: usize = 32;

/// A row's failure: error kind code and message.
type RowError = Option<(&'static str, String)>;

/// Where each row's Willis ratios come from.
enum Ratios<'a> {
    /// The train's own ratios for every row.
    Nominal(Vec<f64>),
    /// One row of `j_G` ratios per scenario.
    Rows(&'a [f64]),
    /// One row of `j_G x 2` tooth counts per scenario, with the sign of each
    /// pair's ratio (-1 external, +1 internal).
    Teeth(&'a [i64], Vec<f64>),
}

impl Ratios<'_> {
    /// Fill `out` with row `r`'s ratios.
    fn fill(&self, train: &Train, r: usize, out: &mut [f64]) -> egt_core::Result<()> {
        let jg = out.len();
        match self {
            Ratios::Nominal(v) => out.copy_from_slice(v),
            Ratios::Rows(a) => {
                out.copy_from_slice(&a[r * jg..(r + 1) * jg]);
                for (m, &t) in out.iter().enumerate() {
                    if !t.is_finite() {
                        return Err(egt_core::Error::spec(
                            format!("ratios[{r}, {m}]"),
                            SpecErrorKind::NonFinite { value: t },
                        ));
                    }
                    if t == 0.0 {
                        return Err(egt_core::Error::spec(
                            format!("ratios[{r}, {m}]"),
                            SpecErrorKind::OutOfRange {
                                value: 0.0,
                                expected: "a Willis ratio is never 0".into(),
                            },
                        ));
                    }
                }
            }
            Ratios::Teeth(z, sign) => {
                for m in 0..jg {
                    let zi = z[(r * jg + m) * 2];
                    let zj = z[(r * jg + m) * 2 + 1];
                    for (side, v) in [(0, zi), (1, zj)] {
                        if v <= 0 || v > i64::from(u32::MAX) {
                            return Err(egt_core::Error::spec(
                                format!("teeth[{r}, {m}, {side}]"),
                                SpecErrorKind::InvalidTeeth { value: v },
                            ));
                        }
                    }
                    if sign[m] > 0.0 && zi == zj {
                        return Err(egt_core::Error::invalid(
                            format!("teeth[{r}, {m}]"),
                            format!(
                                "gear pair `{}` is an internal mesh and needs different tooth counts",
                                train.gears()[m].name
                            ),
                        ));
                    }
                    #[allow(clippy::cast_precision_loss)]
                    {
                        out[m] = sign[m] * zj as f64 / zi as f64;
                    }
                }
            }
        }
        Ok(())
    }
}

/// The ratio source from the optional `ratios` / `teeth` arrays.
fn ratio_source<'a>(
    train: &Train,
    rows: usize,
    ratios: Option<&'a PyReadonlyArray2<'_, f64>>,
    teeth: Option<&'a PyReadonlyArray3<'_, i64>>,
) -> Result<Ratios<'a>> {
    let jg = train.gears().len();
    match (ratios, teeth) {
        (Some(_), Some(_)) => Err(value_error("give either `ratios` or `teeth`, not both")),
        (Some(a), None) => {
            check_shape(a.shape(), &[rows, jg], "ratios")?;
            Ok(Ratios::Rows(slice(a.as_slice())?))
        }
        (None, Some(z)) => {
            check_shape(z.shape(), &[rows, jg, 2], "teeth")?;
            let sign = train
                .gears()
                .iter()
                .map(|g| match (g.mesh, &g.ratio) {
                    (Some(MeshKind::External), _) => Ok(-1.0),
                    (Some(MeshKind::Internal), _) => Ok(1.0),
                    (None, Some(r)) => Ok(r.value.signum()),
                    (None, None) => Err(AnalysisError::MissingData {
                        what: format!("the mesh kind of gear pair `{}`", g.name),
                        analysis: "ratios from tooth counts".into(),
                        hint: format!("give `mesh` at {}", g.path),
                    }),
                })
                .collect::<std::result::Result<Vec<f64>, _>>()
                .map_err(egt_core::Error::from)?;
            Ok(Ratios::Teeth(slice(z.as_slice())?, sign))
        }
        (None, None) => Ok(Ratios::Nominal(train.ratios()?)),
    }
}

fn slice<T>(s: std::result::Result<&[T], numpy::AsSliceError>) -> Result<&[T]> {
    s.map_err(|_| value_error("arrays must be C-contiguous"))
}

fn check_shape(got: &[usize], want: &[usize], what: &str) -> Result<()> {
    if got == want {
        Ok(())
    } else {
        Err(value_error(format!(
            "`{what}` has shape {got:?}, expected {want:?}"
        )))
    }
}

/// Run `body` for every row in parallel with per-worker state from `init`,
/// catching panics per row. `body` fills the row's outputs or fails.
fn run_rows<S, O, I, B>(
    rows: usize,
    threads: Option<usize>,
    outs: &mut [O],
    errs: &mut [RowError],
    init: I,
    body: B,
) -> Result<()>
where
    O: Send,
    I: Fn() -> S + Sync + Send,
    B: Fn(&mut S, usize, &mut O) -> egt_core::Result<()> + Sync + Send,
{
    debug_assert_eq!(outs.len(), rows);
    let mut work = || {
        outs.par_iter_mut()
            .zip(errs.par_iter_mut())
            .enumerate()
            .with_min_len(MIN_ROWS_PER_TASK)
            .for_each_init(&init, |state, (r, (out, err))| {
                *err = match catch_unwind(AssertUnwindSafe(|| body(state, r, out))) {
                    Ok(Ok(())) => None,
                    Ok(Err(e)) => Some((kind(&e), e.to_string())),
                    Err(p) => Some(("panic", format!("internal error: {}", panic_message(&*p)))),
                };
            });
    };
    match threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
            .map_err(|e| value_error(e.to_string()))?
            .install(work),
        None => work(),
    }
    Ok(())
}

/// Per-row outputs of a kinematic batch: speeds of every link, condition, residual.
struct KinRow<'a> {
    speed: &'a mut [f64],
    condition: &'a mut f64,
    residual: &'a mut f64,
}

/// Speeds of every link for many scenarios (rows of input speeds and of ratios
/// or tooth counts).
#[pyfunction]
#[pyo3(signature = (core, inputs, speeds, ratios = None, teeth = None, threads = None))]
pub fn batch_kinematics<'py>(
    py: Python<'py>,
    core: &TrainCore,
    inputs: Vec<String>,
    speeds: PyReadonlyArray2<'py, f64>,
    ratios: Option<PyReadonlyArray2<'py, f64>>,
    teeth: Option<PyReadonlyArray3<'py, i64>>,
    threads: Option<usize>,
) -> Result<Bound<'py, PyDict>> {
    guard(|| {
        let train = &core.train;
        let ids = convert::links(train, &inputs, "inputs")?;
        let plan = KinematicsPlan::new(train, &ids)?;
        let rows = speeds.shape()[0];
        check_shape(speeds.shape(), &[rows, ids.len()], "speeds")?;
        let w_in = slice(speeds.as_slice())?;
        let src = ratio_source(train, rows, ratios.as_ref(), teeth.as_ref())?;
        let (nl, jg, f) = (train.links().len(), train.gears().len(), ids.len());

        let mut speed = vec![0.0; rows * nl];
        let mut condition = vec![0.0; rows];
        let mut residual = vec![0.0; rows];
        let mut errs: Vec<RowError> = vec![None; rows];
        py.detach(|| {
            let mut outs: Vec<KinRow<'_>> = speed
                .chunks_mut(nl.max(1))
                .zip(condition.iter_mut())
                .zip(residual.iter_mut())
                .map(|((speed, condition), residual)| KinRow {
                    speed,
                    condition,
                    residual,
                })
                .collect();
            if nl == 0 {
                outs.clear();
            }
            run_rows(
                rows,
                threads,
                &mut outs,
                &mut errs,
                || (plan.clone(), vec![0.0; jg]),
                |(plan, taus), r, out| {
                    src.fill(train, r, taus)?;
                    let w = &w_in[r * f..(r + 1) * f];
                    for (k, v) in w.iter().enumerate() {
                        if !v.is_finite() {
                            return Err(egt_core::Error::spec(
                                format!("speeds[{r}, {k}]"),
                                SpecErrorKind::NonFinite { value: *v },
                            ));
                        }
                    }
                    let solved = plan.solve(taus, w, out.speed);
                    match solved {
                        Ok(c) => {
                            *out.condition = c;
                            *out.residual = willis_residual(train, taus, out.speed);
                            Ok(())
                        }
                        Err(e) => {
                            out.speed.iter_mut().for_each(|v| *v = 0.0);
                            Err(e)
                        }
                    }
                },
            )
        })?;
        let d = PyDict::new(py);
        d.set_item("speed", mat2(py, rows, nl, speed)?)?;
        d.set_item("condition", vec1(py, condition))?;
        d.set_item("residual", vec1(py, residual))?;
        d.set_item(
            "known",
            vec1(
                py,
                train.links().iter().map(|l| l.sized).collect::<Vec<_>>(),
            ),
        )?;
        errors_into(py, &d, &errs)?;
        Ok(d)
    })
}

/// `ok` mask and the failed rows' `(row, kind, message)`.
fn errors_into(py: Python<'_>, d: &Bound<'_, PyDict>, errs: &[RowError]) -> Result<()> {
    d.set_item(
        "ok",
        vec1(py, errs.iter().map(Option::is_none).collect::<Vec<_>>()),
    )?;
    d.set_item(
        "errors",
        errs.iter()
            .enumerate()
            .filter_map(|(r, e)| e.as_ref().map(|(k, m)| (r, *k, m.clone())))
            .collect::<Vec<_>>(),
    )?;
    Ok(())
}

/// One link's contribution to [M] (eq. 3-4): its coordinate, copies, nominal
/// data and the eq. (4) chain of (coordinate, offset) terms.
struct MassTerm {
    coordinate: usize,
    copies: f64,
    inertia: f64,
    mass: f64,
    sized: bool,
    name: String,
    /// The chain of carrier coordinates and offsets, or why it is unknown.
    chain: std::result::Result<Vec<(usize, f64)>, egt_core::Error>,
}

fn mass_terms(train: &Train) -> Vec<MassTerm> {
    let (offsets, _) = train.axis_offsets();
    let mut out = Vec::new();
    for (i, l) in train.links().iter().enumerate() {
        let id = LinkId::from_index(i);
        let Some(c) = train.coordinate(id) else {
            continue;
        };
        let chain = train
            .offset_chain(id)
            .into_iter()
            .filter_map(|(carrier, lv)| {
                let d = offsets.iter().find(|o| o.levels == lv).map(|o| o.distance);
                match d {
                    None => Some(Err(AnalysisError::MissingData {
                        what: format!(
                            "the offset between axis levels `{}` and `{}`",
                            train.level_name(lv[0]),
                            train.level_name(lv[1])
                        ),
                        analysis: format!("the kinetic energy of link `{}` (eq. 4)", l.name),
                        hint: "give [[offsets]] or the pitch radii of a gear pair meshing across those levels".into(),
                    }
                    .into())),
                    Some(d) => train.coordinate(carrier).map(|k| Ok((k, d))),
                }
            })
            .collect();
        out.push(MassTerm {
            coordinate: c,
            copies: f64::from(l.copies),
            inertia: l.inertia.unwrap_or(0.0),
            mass: l.mass.unwrap_or(0.0),
            sized: l.sized,
            name: l.name.clone(),
            chain,
        });
    }
    out
}

/// Per-row overrides of link data: the link's slot among the mass terms and a
/// column of the override array.
fn overrides(
    train: &Train,
    terms: &[MassTerm],
    names: &[String],
    what: &str,
) -> Result<Vec<usize>> {
    names
        .iter()
        .map(|n| {
            let l = convert::link(train, n, &format!("{what}.{n}"))?;
            let c = train.coordinate(l).ok_or_else(|| {
                value_error(format!("`{what}` cannot set data of the frame `{n}`"))
            })?;
            terms
                .iter()
                .position(|t| t.coordinate == c)
                .ok_or_else(|| value_error(format!("link `{n}` has no mass term")))
        })
        .collect()
}

/// Fill the row-major [M] for one row (eq. 3-5 with the row's inertias and masses).
fn fill_mass(
    terms: &[MassTerm],
    inertia: &[f64],
    mass: &[f64],
    n: usize,
    m: &mut [f64],
    r: usize,
) -> egt_core::Result<()> {
    m.iter_mut().for_each(|v| *v = 0.0);
    for (t, (&i, &ms)) in terms.iter().zip(inertia.iter().zip(mass)) {
        for (v, what) in [(i, "inertia"), (ms, "mass")] {
            if !v.is_finite() {
                return Err(egt_core::Error::spec(
                    format!("{what}[{r}] of `{}`", t.name),
                    SpecErrorKind::NonFinite { value: v },
                ));
            }
            if v < 0.0 {
                return Err(egt_core::Error::spec(
                    format!("{what}[{r}] of `{}`", t.name),
                    SpecErrorKind::OutOfRange {
                        value: v,
                        expected: "must be >= 0".into(),
                    },
                ));
            }
        }
        if i > 0.0 {
            if !t.sized {
                return Err(AnalysisError::MissingData {
                    what: format!("the tooth count of planet `{}`", t.name),
                    analysis: "its rotational kinetic energy (it has an inertia)".into(),
                    hint: "give `teeth.planet` in its planetary set".into(),
                }
                .into());
            }
            m[t.coordinate * n + t.coordinate] += t.copies * i;
        }
        if ms > 0.0 {
            let chain = t.chain.as_ref().map_err(Clone::clone)?;
            for &(a, da) in chain {
                for &(b, db) in chain {
                    m[a * n + b] += t.copies * ms * da * db;
                }
            }
        }
    }
    Ok(())
}

/// Per-row outputs of a dynamics batch.
struct DynRow<'a> {
    driving: &'a mut [f64],
    acceleration: &'a mut [f64],
    multipliers: &'a mut [f64],
    conditions: &'a mut [f64],
}

/// Per-worker state of a dynamics batch.
struct DynState {
    plan: InverseDynamicsPlan,
    taus: Vec<f64>,
    inertia: Vec<f64>,
    mass: Vec<f64>,
    m: Vec<f64>,
    q: Vec<f64>,
}

/// Inverse dynamics for many scenarios: rows of prescribed accelerations, known
/// torques, ratios or teeth, and link inertias and masses.
#[pyfunction]
#[pyo3(signature = (
    core, driving, accelerated, alpha, torque_links, torques,
    ratios = None, teeth = None, inertia_links = Vec::new(), inertias = None,
    mass_links = Vec::new(), masses = None, engaged = Vec::new(), threads = None
))]
#[allow(clippy::too_many_arguments)]
pub fn batch_dynamics<'py>(
    py: Python<'py>,
    core: &TrainCore,
    driving: Vec<String>,
    accelerated: Vec<String>,
    alpha: PyReadonlyArray2<'py, f64>,
    torque_links: Vec<String>,
    torques: PyReadonlyArray2<'py, f64>,
    ratios: Option<PyReadonlyArray2<'py, f64>>,
    teeth: Option<PyReadonlyArray3<'py, i64>>,
    inertia_links: Vec<String>,
    inertias: Option<PyReadonlyArray2<'py, f64>>,
    mass_links: Vec<String>,
    masses: Option<PyReadonlyArray2<'py, f64>>,
    engaged: Vec<String>,
    threads: Option<usize>,
) -> Result<Bound<'py, PyDict>> {
    guard(|| {
        let train = &core.train;
        let drv = convert::links(train, &driving, "driving")?;
        let acc = convert::links(train, &accelerated, "accelerations")?;
        let extras: Vec<Extra> = convert::engaged(train, &engaged)?;
        let plan = InverseDynamicsPlan::new(train, &acc, &drv, &extras)?;
        let rows = alpha.shape()[0];
        let f = drv.len();
        check_shape(alpha.shape(), &[rows, f], "accelerations")?;
        let alpha = slice(alpha.as_slice())?;
        let tl = convert::links(train, &torque_links, "torques")?;
        check_shape(torques.shape(), &[rows, tl.len()], "torques")?;
        let tq = slice(torques.as_slice())?;
        let tcol: Vec<Option<usize>> = tl.iter().map(|&l| train.coordinate(l)).collect();
        let src = ratio_source(train, rows, ratios.as_ref(), teeth.as_ref())?;

        let terms = mass_terms(train);
        let ipos = overrides(train, &terms, &inertia_links, "inertias")?;
        let mpos = overrides(train, &terms, &mass_links, "masses")?;
        let iarr = match &inertias {
            Some(a) => {
                check_shape(a.shape(), &[rows, ipos.len()], "inertias")?;
                slice(a.as_slice())?
            }
            None if ipos.is_empty() => &[][..],
            None => return Err(value_error("`inertia_links` given without `inertias`")),
        };
        let marr = match &masses {
            Some(a) => {
                check_shape(a.shape(), &[rows, mpos.len()], "masses")?;
                slice(a.as_slice())?
            }
            None if mpos.is_empty() => &[][..],
            None => return Err(value_error("`mass_links` given without `masses`")),
        };
        let (nl, jg, n, c) = (
            train.links().len(),
            train.gears().len(),
            train.coordinates().len(),
            plan.constraints(),
        );
        let coords: Vec<LinkId> = train.coordinates().to_vec();

        let mut out_drv = vec![0.0; rows * f];
        let mut out_acc = vec![0.0; rows * nl];
        let mut out_lam = vec![0.0; rows * c];
        let mut out_cond = vec![0.0; rows * 2];
        let mut errs: Vec<RowError> = vec![None; rows];
        py.detach(|| {
            let mut outs: Vec<DynRow<'_>> = Vec::with_capacity(rows);
            let mut d_it = out_drv.chunks_mut(f.max(1));
            let mut a_it = out_acc.chunks_mut(nl.max(1));
            let mut l_it = out_lam.chunks_mut(c.max(1));
            let mut k_it = out_cond.chunks_mut(2);
            for _ in 0..rows {
                let (Some(driving), Some(acceleration), Some(multipliers), Some(conditions)) = (
                    if f == 0 {
                        Some(&mut [][..])
                    } else {
                        d_it.next()
                    },
                    a_it.next(),
                    if c == 0 {
                        Some(&mut [][..])
                    } else {
                        l_it.next()
                    },
                    k_it.next(),
                ) else {
                    break;
                };
                outs.push(DynRow {
                    driving,
                    acceleration,
                    multipliers,
                    conditions,
                });
            }
            run_rows(
                rows,
                threads,
                &mut outs,
                &mut errs,
                || DynState {
                    plan: plan.clone(),
                    taus: vec![0.0; jg],
                    inertia: terms.iter().map(|t| t.inertia).collect(),
                    mass: terms.iter().map(|t| t.mass).collect(),
                    m: vec![0.0; n * n],
                    q: vec![0.0; n],
                },
                |s, r, out| {
                    src.fill(train, r, &mut s.taus)?;
                    let a = &alpha[r * f..(r + 1) * f];
                    for (k, v) in a.iter().enumerate() {
                        if !v.is_finite() {
                            return Err(egt_core::Error::spec(
                                format!("accelerations[{r}, {k}]"),
                                SpecErrorKind::NonFinite { value: *v },
                            ));
                        }
                    }
                    s.q.iter_mut().for_each(|v| *v = 0.0);
                    let trow = &tq[r * tl.len()..(r + 1) * tl.len()];
                    for (k, (&t, col)) in trow.iter().zip(&tcol).enumerate() {
                        if !t.is_finite() {
                            return Err(egt_core::Error::spec(
                                format!("torques[{r}, {k}]"),
                                SpecErrorKind::NonFinite { value: t },
                            ));
                        }
                        if let Some(col) = col {
                            s.q[*col] += t;
                        }
                    }
                    if a.iter().any(|&v| v != 0.0) {
                        for (k, &p) in ipos.iter().enumerate() {
                            s.inertia[p] = iarr[r * ipos.len() + k];
                        }
                        for (k, &p) in mpos.iter().enumerate() {
                            s.mass[p] = marr[r * mpos.len() + k];
                        }
                        fill_mass(&terms, &s.inertia, &s.mass, n, &mut s.m, r)?;
                    } else {
                        s.m.iter_mut().for_each(|v| *v = 0.0);
                    }
                    s.plan.solve(&s.taus, &s.taus, &s.m, &s.q, a)?;
                    out.driving.copy_from_slice(s.plan.driving_torques());
                    out.multipliers.copy_from_slice(s.plan.multipliers());
                    for (k, l) in coords.iter().enumerate() {
                        out.acceleration[l.index()] = s.plan.accelerations()[k];
                    }
                    out.conditions.copy_from_slice(&s.plan.conditions());
                    Ok(())
                },
            )
        })?;
        let d = PyDict::new(py);
        d.set_item("driving_torques", mat2(py, rows, f, out_drv)?)?;
        d.set_item("acceleration", mat2(py, rows, nl, out_acc)?)?;
        d.set_item("multipliers", mat2(py, rows, c, out_lam)?)?;
        d.set_item("conditions", mat2_of(py, rows, 2, out_cond)?)?;
        errors_into(py, &d, &errs)?;
        Ok(d)
    })
}
