//! `mesorve._mesorve`: the Python binding (PyO3 + numpy) over the library's safe Rust API.
//! A `Model` is one scene, meshed once; `Points` are `n` instances of it updated together
//! by `rve::model::batch::update_batch` with the GIL released. The Python package
//! `mesorve` re-exports these classes (see docs/python.md).

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{AllowTypeChange, PyArray1, PyArray2, PyArray3, PyArrayLike2, PyArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use rve::model::batch::{update_batch, BatchOutputs, BatchStep, PointReport, Reliability};
use rve::{Instance, Scene, TangentRequest};

create_exception!(
    _mesorve,
    RveError,
    PyException,
    "A library error; `index` is the failing point (None for a whole-batch error) and \
     `message` the library's message. A batch that failed at several points also has \
     `indices` and `messages`."
);

/// `RveError` for point `index` (or none) with the library's message.
fn rve_error(py: Python<'_>, failures: &[(usize, String)], whole: Option<String>) -> PyErr {
    let (index, message) = match (&whole, failures.first()) {
        (Some(m), _) => (None, m.clone()),
        (None, Some((k, m))) => (Some(*k), m.clone()),
        (None, None) => (None, "no failure".into()),
    };
    let text = match index {
        Some(k) if failures.len() > 1 => {
            format!(
                "point {k}: {message} (and {} more points)",
                failures.len() - 1
            )
        }
        Some(k) => format!("point {k}: {message}"),
        None => message.clone(),
    };
    let err = RveError::new_err(text);
    let value = err.value(py);
    let indices: Vec<usize> = failures.iter().map(|(k, _)| *k).collect();
    let messages: Vec<String> = failures.iter().map(|(_, m)| m.clone()).collect();
    // Setting attributes on a fresh exception object cannot fail short of memory.
    let _ = value.setattr("index", index);
    let _ = value.setattr("message", message);
    let _ = value.setattr("indices", indices);
    let _ = value.setattr("messages", messages);
    err
}

fn whole_error(py: Python<'_>, e: rve::Error) -> PyErr {
    rve_error(py, &[], Some(e.to_string()))
}

/// One scene, meshed once: `Model()` is the paper's RVE (section 5.2, embedded in the
/// library), `Model("scene.toml")` a scene file, `Model(text="...")` a scene's TOML text
/// (relative paths in it resolve against `base_dir`, default the working directory).
#[pyclass(module = "mesorve._mesorve", frozen)]
struct Model {
    model: Arc<rve::Model>,
    path: Vec<[f64; 3]>,
}

#[pymethods]
impl Model {
    #[new]
    #[pyo3(signature = (scene=None, *, text=None, base_dir=None))]
    fn new(
        py: Python<'_>,
        scene: Option<PathBuf>,
        text: Option<&str>,
        base_dir: Option<PathBuf>,
    ) -> PyResult<Self> {
        let scene = match (scene, text) {
            (Some(_), Some(_)) => {
                return Err(PyValueError::new_err(
                    "give a scene path or text=, not both",
                ))
            }
            (Some(path), None) => Scene::from_file(path),
            (None, Some(t)) => Scene::from_toml_str(t, base_dir.unwrap_or_default()),
            (None, None) => Scene::embedded_default(),
        }
        .map_err(|e| whole_error(py, e))?;
        let model = py
            .allow_threads(|| rve::Model::from_scene(&scene))
            .map_err(|e| whole_error(py, e))?;
        let path = rve::scene::path_points(&scene.spec.path);
        Ok(Model {
            model: Arc::new(model),
            path,
        })
    }

    /// This model regularized for a host element of characteristic length
    /// `element_length` (the scene's length unit; the scene needs
    /// `effects.regularization`): the cell's cracks soften over `L_cell / element_length`
    /// times their length, so that an element crossed by one crack dissipates the cell's
    /// fracture energy per unit crack length whatever its size. One model per scene and
    /// length; every length shares the scene's mesh.
    fn for_element(&self, py: Python<'_>, element_length: f64) -> PyResult<Model> {
        let model = rve::model::cache::regularized(&self.model, element_length)
            .map_err(|e| whole_error(py, e))?;
        Ok(Model {
            model,
            path: self.path.clone(),
        })
    }

    /// `n` virgin points (instances) of this model; `threads` as `Points.threads`.
    #[pyo3(signature = (n, threads=1))]
    fn points(&self, n: usize, threads: usize) -> Points {
        Points {
            instances: (0..n).map(|_| Instance::new(self.model.clone())).collect(),
            reports: vec![PointReport::default(); n],
            model: self.model.clone(),
            threads,
        }
    }

    /// The scene's strain path (`[[path]]`), shape (m, 3), as `rve run` follows it.
    fn path<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        PyArray1::from_slice(py, self.path.as_flattened()).reshape([self.path.len(), 3])
    }

    /// The homogenized elastic tangent of the virgin RVE, (3, 3), `D[i, j] = d s_i / d e_j`.
    fn elastic_tangent<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        PyArray1::from_slice(py, &self.model.elastic_tangent()).reshape([3, 3])
    }

    fn __repr__(&self) -> String {
        format!("mesorve.Model(path increments: {})", self.path.len())
    }
}

/// What `Points.update` returns: the stresses and, unless not requested, the tangents.
type Update<'py> = (Bound<'py, PyArray2<f64>>, Option<Bound<'py, PyArray3<f64>>>);

/// `n` material points of one model, updated together (trial), then committed or reverted.
#[pyclass(module = "mesorve._mesorve")]
struct Points {
    model: Arc<rve::Model>,
    instances: Vec<Instance>,
    reports: Vec<PointReport>,
    /// 1: the calling thread; k > 1: a pool of k threads; 0: one per core.
    #[pyo3(get, set)]
    threads: usize,
}

fn tangent_request(name: &str) -> PyResult<TangentRequest> {
    match name {
        "consistent" => Ok(TangentRequest::Consistent),
        "elastic" => Ok(TangentRequest::Elastic),
        "none" => Ok(TangentRequest::None),
        other => Err(PyValueError::new_err(format!(
            "tangent = {other:?}: use 'consistent', 'elastic' or 'none'"
        ))),
    }
}

impl Points {
    fn check_index(&self, k: usize) -> PyResult<()> {
        if k < self.instances.len() {
            Ok(())
        } else {
            Err(PyIndexError::new_err(format!(
                "point {k} out of range ({} points)",
                self.instances.len()
            )))
        }
    }

    /// Runs `f` on every point; the failures raise one `RveError`.
    fn each(
        &mut self,
        py: Python<'_>,
        f: impl Fn(&mut Instance) -> rve::Result<()>,
    ) -> PyResult<()> {
        let failures: Vec<(usize, String)> = self
            .instances
            .iter_mut()
            .enumerate()
            .filter_map(|(k, i)| f(i).err().map(|e| (k, e.to_string())))
            .collect();
        if failures.is_empty() {
            Ok(())
        } else {
            Err(rve_error(py, &failures, None))
        }
    }
}

#[pymethods]
impl Points {
    fn __len__(&self) -> usize {
        self.instances.len()
    }

    /// Trial update of every point: `eps` (n, 3) = [eps_xx, eps_yy, gamma_xy] (engineering
    /// shear) over a host time increment `dtime` (IMPL-EX scenes; 0: as long as the
    /// last). Returns `(sig, D)`: stresses (n, 3) and tangents (n, 3, 3),
    /// `D[k, i, j] = d sig_i / d eps_j` (`tangent`: 'consistent', 'elastic' or 'none',
    /// then D is None). Raises `RveError` (with the failing point's index) when a point
    /// fails; the others keep their trial. The GIL is released during the solve.
    #[pyo3(signature = (eps, dtime=0.0, tangent="consistent"))]
    fn update<'py>(
        &mut self,
        py: Python<'py>,
        eps: PyArrayLike2<'py, f64, AllowTypeChange>,
        dtime: f64,
        tangent: &str,
    ) -> PyResult<Update<'py>> {
        let request = tangent_request(tangent)?;
        let n = self.instances.len();
        let eps = eps.as_array();
        if eps.shape() != [n, 3] {
            return Err(PyValueError::new_err(format!(
                "eps has shape {:?}; expected ({n}, 3)",
                eps.shape()
            )));
        }
        let strains: Vec<[f64; 3]> = eps.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
        let mut stresses = vec![[0.0; 3]; n];
        let mut tangents = (request != TangentRequest::None).then(|| vec![[0.0; 9]; n]);
        let step = BatchStep {
            dtime,
            request,
            threads: self.threads,
        };
        let (instances, reports) = (&mut self.instances, &mut self.reports);
        let result = py.allow_threads(|| {
            let out = BatchOutputs {
                stresses: &mut stresses,
                tangents: tangents.as_deref_mut(),
                reports,
            };
            update_batch(instances, &strains, step, out).map(|f| {
                f.into_iter()
                    .map(|(k, e)| (k, e.to_string()))
                    .collect::<Vec<_>>()
            })
        });
        let failures = result.map_err(|e| whole_error(py, e))?;
        if !failures.is_empty() {
            return Err(rve_error(py, &failures, None));
        }
        let sig = PyArray1::from_slice(py, stresses.as_flattened()).reshape([n, 3])?;
        let d = match tangents {
            Some(t) => Some(PyArray1::from_slice(py, t.as_flattened()).reshape([n, 3, 3])?),
            None => None,
        };
        Ok((sig, d))
    }

    /// Accepts every point's trial (the host's increment converged). `RveError` names a
    /// point without a trial (its update failed, or none since the last commit).
    fn commit(&mut self, py: Python<'_>) -> PyResult<()> {
        self.each(py, |i| i.commit())
    }

    /// Discards every point's trial; the committed states stay.
    fn revert(&mut self) {
        self.instances.iter_mut().for_each(Instance::revert);
    }

    /// Returns every point to the virgin state.
    fn reset(&mut self) {
        self.instances.iter_mut().for_each(Instance::reset);
    }

    /// The last update's report, a dict of arrays of n: iterations, substeps,
    /// factorizations, reliability (0 failed, 1 reliable, 2 substepped),
    /// suggested_step_ratio (UMAT's PNEWDT), s_zz, fast (answered without a solve),
    /// shared_from (-1: solved itself) and error_estimate (the IMPL-EX estimate over solver.step_tolerance; 0 without one).
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.reports;
        let d = PyDict::new(py);
        let u = |f: fn(&PointReport) -> u32| PyArray1::from_iter(py, r.iter().map(f));
        let x = |f: fn(&PointReport) -> f64| PyArray1::from_iter(py, r.iter().map(f));
        d.set_item("iterations", u(|p| p.iterations))?;
        d.set_item("substeps", u(|p| p.substeps))?;
        d.set_item("factorizations", u(|p| p.factorizations))?;
        d.set_item(
            "reliability",
            PyArray1::from_iter(py, r.iter().map(|p| reliability_code(p.reliability))),
        )?;
        d.set_item("suggested_step_ratio", x(|p| p.suggested_step_ratio))?;
        d.set_item("error_estimate", x(|p| p.error_estimate))?;
        d.set_item("s_zz", x(|p| p.s_zz))?;
        d.set_item("fast", PyArray1::from_iter(py, r.iter().map(|p| p.fast)))?;
        d.set_item(
            "shared_from",
            PyArray1::from_iter(py, r.iter().map(|p| p.shared_from.map_or(-1, |k| k as i64))),
        )?;
        Ok(d)
    }

    /// Point `k`'s committed state as checkpoint bytes (the C API's `rve_state_save`).
    fn state<'py>(&self, py: Python<'py>, k: usize) -> PyResult<Bound<'py, PyBytes>> {
        self.check_index(k)?;
        let bytes = self.instances[k]
            .save_state()
            .map_err(|e| point_error(py, k, e))?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// Replaces point `k`'s committed state by `data` (from `state` of a point of the
    /// same scene); its trial is discarded.
    fn load_state(&mut self, py: Python<'_>, k: usize, data: &[u8]) -> PyResult<()> {
        self.check_index(k)?;
        self.instances[k]
            .load_state(data)
            .map_err(|e| point_error(py, k, e))
    }

    /// Every point's committed state in one bytes object (`Model.points_from_bytes`).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let mut out = Vec::from(BATCH_MAGIC);
        out.extend_from_slice(&(self.instances.len() as u64).to_le_bytes());
        for (k, i) in self.instances.iter().enumerate() {
            let bytes = i.save_state().map_err(|e| point_error(py, k, e))?;
            out.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
            out.extend_from_slice(&bytes);
        }
        Ok(PyBytes::new(py, &out))
    }

    /// Loads every point's committed state from `to_bytes` output of as many points.
    fn load_bytes(&mut self, py: Python<'_>, data: &[u8]) -> PyResult<()> {
        let states = split_batch(data, self.instances.len())?;
        for (k, (i, s)) in self.instances.iter_mut().zip(states).enumerate() {
            i.load_state(s).map_err(|e| point_error(py, k, e))?;
        }
        Ok(())
    }

    fn __repr__(&self) -> String {
        format!(
            "mesorve.Points(n={}, threads={}, model unknowns={})",
            self.instances.len(),
            self.threads,
            self.model.unknowns()
        )
    }
}

fn reliability_code(r: Reliability) -> i8 {
    match r {
        Reliability::Failed => 0,
        Reliability::Reliable => 1,
        Reliability::Substepped => 2,
    }
}

fn point_error(py: Python<'_>, k: usize, e: rve::Error) -> PyErr {
    rve_error(py, &[(k, e.to_string())], None)
}

/// The header of `Points.to_bytes`: magic, then the point count, then each point's state
/// as (length, bytes), little-endian u64 lengths.
const BATCH_MAGIC: &[u8; 8] = b"MRVEPTS1";

/// The `n` point states of `to_bytes` output.
fn split_batch(data: &[u8], n: usize) -> PyResult<Vec<&[u8]>> {
    let bad = |why: &str| PyValueError::new_err(format!("not Points.to_bytes output: {why}"));
    let rest = data
        .strip_prefix(BATCH_MAGIC)
        .ok_or_else(|| bad("no header"))?;
    let (count, mut rest) = take_u64(rest).ok_or_else(|| bad("truncated"))?;
    if count != n as u64 {
        return Err(bad(&format!("{count} points, these are {n}")));
    }
    let mut states = Vec::with_capacity(n);
    for _ in 0..n {
        let (len, after) = take_u64(rest).ok_or_else(|| bad("truncated"))?;
        let len = usize::try_from(len).map_err(|_| bad("length"))?;
        if after.len() < len {
            return Err(bad("truncated"));
        }
        states.push(&after[..len]);
        rest = &after[len..];
    }
    if !rest.is_empty() {
        return Err(bad("trailing bytes"));
    }
    Ok(states)
}

fn take_u64(b: &[u8]) -> Option<(u64, &[u8])> {
    let (head, rest) = b.split_first_chunk::<8>()?;
    Some((u64::from_le_bytes(*head), rest))
}

#[pymodule]
fn _mesorve(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Model>()?;
    m.add_class::<Points>()?;
    m.add("RveError", m.py().get_type::<RveError>())?;
    m.add("VERSION", rve::VERSION)?;
    Ok(())
}
