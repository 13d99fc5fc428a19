//! The `poser` Python module (compiled part, `poser._poser`): the poser library for notebooks
//! and Blender, with no logic of its own. Every call goes to the same library function the CLI
//! uses, so results are identical to the CLI's (projections bit for bit, render bytes equal).
//!
//! | Python | library | CLI twin |
//! |---|---|---|
//! | `poser.load(path, set={...})` → `Scene` | `scene::load` | every command's `SCENE --set` |
//! | `Scene.explain()` | `explain::explain` | `poser explain` |
//! | `Scene.to_dict()` | the resolved model, serialised | `poser explain --json` |
//! | `Scene.poses`, `Scene.cameras` | `Model::poses`, `truth::camera_truth` | `truth.json` |
//! | `Scene.project(points, camera=, frame=, pose=, channel=)` | `Projector::project_points` | `poser project` |
//! | `Scene.truth()` | `truth::compute` | `poser truth` (`truth.json`) |
//! | `Scene.plan()` | `plan::survey::survey` | `poser plan --json` (`survey`) |
//! | `Scene.dive()` | `plan::dive::plan_dive` | `poser dive --json` |
//! | `Scene.render(pose, camera=, samples=, scale=)` | `backend::native::render_one` | `poser render` (`<image>.exr`) |
//! | `Scene.compile(backend, out_dir)` | `backend::Backend::compile` | `poser compile` |
//!
//! Errors come back as exceptions: `poser.SceneError` (an invalid scene; `.diagnostics` holds
//! file, line, column, message and help of each), `ValueError` (a bad argument), and
//! `poser.PoserError` (a run that failed). Long computations release the GIL.

use numpy::{IntoPyArray, PyArray1, PyArrayLikeDyn, PyArrayMethods, PyUntypedArrayMethods};
use poser::backend::Backend;
use poser::model::{Model, Pose};
use poser::scene::diag::{Diagnostic as Diag, Severity};
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

pyo3::create_exception!(
    poser,
    PoserError,
    PyException,
    "A poser run failed (I/O, a renderer, a scene the command cannot handle)."
);
pyo3::create_exception!(
    poser,
    SceneError,
    PoserError,
    "The scene is invalid; `.diagnostics` holds each error and warning (file, line, column, \
     message, help)."
);

fn failed(e: String) -> PyErr {
    PoserError::new_err(e)
}

/// One diagnostic of a scene: where (file, line, column; `None` when the diagnostic has no
/// place in a file), what, and the hint.
#[pyclass(frozen, module = "poser", get_all)]
#[derive(Clone)]
struct Diagnostic {
    /// `"error"` or `"warning"`.
    severity: &'static str,
    /// Stable code, e.g. `E0100` (docs/format.md lists them).
    code: &'static str,
    message: String,
    file: Option<String>,
    line: Option<usize>,
    column: Option<usize>,
    help: Option<String>,
    /// The full text the CLI prints: source line, caret, help.
    rendered: String,
}

#[pymethods]
impl Diagnostic {
    fn __repr__(&self) -> String {
        match (&self.file, self.line, self.column) {
            (Some(f), Some(l), Some(c)) => format!(
                "<Diagnostic {} {} at {f}:{l}:{c}: {}>",
                self.severity, self.code, self.message
            ),
            _ => format!(
                "<Diagnostic {} {}: {}>",
                self.severity, self.code, self.message
            ),
        }
    }

    fn __str__(&self) -> String {
        self.rendered.clone()
    }
}

impl Diagnostic {
    fn from(d: &Diag) -> Diagnostic {
        let pos = d.position();
        Diagnostic {
            severity: match d.severity {
                Severity::Error => "error",
                Severity::Warning => "warning",
            },
            code: d.code,
            message: d.message.clone(),
            file: pos.map(|p| p.0.to_string()),
            line: pos.map(|p| p.1),
            column: pos.map(|p| p.2),
            help: d.help.clone(),
            rendered: d.rendered.clone(),
        }
    }
}

fn diagnostics<'py>(py: Python<'py>, ds: &[Diag]) -> PyResult<Bound<'py, PyList>> {
    PyList::new(py, ds.iter().map(Diagnostic::from))
}

/// A `--set` value from a Python value: TOML text (bool, int, float, str, lists of these).
fn toml_value(v: &Bound<'_, PyAny>) -> PyResult<toml::Value> {
    use pyo3::types::{PyBool, PyFloat, PyInt, PyString};
    if v.is_instance_of::<PyBool>() {
        Ok(toml::Value::Boolean(v.extract()?))
    } else if v.is_instance_of::<PyInt>() {
        Ok(toml::Value::Integer(v.extract()?))
    } else if v.is_instance_of::<PyFloat>() {
        Ok(toml::Value::Float(v.extract()?))
    } else if v.is_instance_of::<PyString>() {
        Ok(toml::Value::String(v.extract()?))
    } else if let Ok(items) = v.extract::<Vec<Bound<'_, PyAny>>>() {
        Ok(toml::Value::Array(
            items.iter().map(toml_value).collect::<PyResult<_>>()?,
        ))
    } else {
        Err(PyValueError::new_err(format!(
            "set: cannot use a {} as a scene value (bool, int, float, str or a list of them; \
             use dotted keys for tables, e.g. {{\"water.temperature\": 12}})",
            v.get_type().name()?
        )))
    }
}

/// Load, validate and resolve a scene file.
///
/// `set` overrides values of the scene like the CLI's `--set KEY=VALUE`, e.g.
/// `{"water.temperature": 12, "render.noise": "5 %"}`. An invalid scene raises
/// `poser.SceneError`, whose `.diagnostics` name file, line and column.
#[pyfunction]
#[pyo3(signature = (path, set = None))]
fn load(py: Python<'_>, path: PathBuf, set: Option<Bound<'_, PyDict>>) -> PyResult<Scene> {
    let mut sets = Vec::new();
    if let Some(d) = set {
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| PyValueError::new_err("set: keys are dotted names (str)"))?;
            sets.push(format!("{key}={}", toml_value(&v)?));
        }
    }
    match py.detach(|| poser::scene::load(&path, &sets)) {
        Ok(loaded) => Ok(Scene {
            warnings: loaded.warnings.iter().map(Diagnostic::from).collect(),
            files: loaded.files,
            model: loaded.model,
        }),
        Err(failure) => {
            let err = SceneError::new_err(failure.render());
            err.value(py)
                .setattr("diagnostics", diagnostics(py, &failure.diagnostics)?)?;
            Err(err)
        }
    }
}

/// A loaded, validated scene: the resolved model every poser command works on.
#[pyclass(frozen, module = "poser")]
struct Scene {
    model: Model,
    warnings: Vec<Diagnostic>,
    files: Vec<PathBuf>,
}

/// `world_from_x` as a 4×4 matrix (rotation and translation; row-major).
fn matrix<'py>(py: Python<'py>, p: &Pose) -> PyResult<Bound<'py, PyAny>> {
    let r = p.rotation;
    let t = p.translation;
    let rows: Vec<Vec<f64>> = vec![
        vec![r.x_axis.x, r.y_axis.x, r.z_axis.x, t.x],
        vec![r.x_axis.y, r.y_axis.y, r.z_axis.y, t.y],
        vec![r.x_axis.z, r.y_axis.z, r.z_axis.z, t.z],
        vec![0.0, 0.0, 0.0, 1.0],
    ];
    Ok(numpy::PyArray2::from_vec2(py, &rows)?.into_any())
}

/// Serialise with serde and read back with Python's `json` (floats round-trip exactly).
fn to_py<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let s = serde_json::to_string(v).map_err(|e| failed(e.to_string()))?;
    py.import("json")?.call_method1("loads", (s,))
}

fn strings<'py>(py: Python<'py>, v: Vec<String>) -> PyResult<Bound<'py, PyAny>> {
    // A numpy array of str (dtype `<U…`), like the numeric arrays beside it.
    let list = PyList::new(py, v)?;
    py.import("numpy")?.call_method1("array", (list, "U"))
}

impl Scene {
    fn camera(&self, camera: Option<&str>) -> PyResult<usize> {
        match camera {
            None => Ok(0),
            Some(name) => self.model.camera_index(name).map_err(PyValueError::new_err),
        }
    }

    fn pose(&self, pose: usize) -> PyResult<usize> {
        if pose < self.model.poses.len() {
            Ok(pose)
        } else {
            Err(PyValueError::new_err(format!(
                "pose {pose} is out of range (the network has {} poses)",
                self.model.poses.len()
            )))
        }
    }
}

#[pymethods]
impl Scene {
    /// The scenario's name.
    #[getter]
    fn name(&self) -> &str {
        &self.model.name
    }

    /// The scene file as given.
    #[getter]
    fn source(&self) -> &str {
        &self.model.source
    }

    /// The scene's warnings (a valid scene may have some), as `poser.Diagnostic`s.
    #[getter]
    fn warnings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        PyList::new(py, self.warnings.iter().cloned())
    }

    /// Every file the scene was read from: the scene, its includes, its assets.
    #[getter]
    fn files(&self) -> Vec<String> {
        self.files
            .iter()
            .map(|p| p.to_string_lossy().into_owned())
            .collect()
    }

    /// The rig poses of the camera network, in order: dicts with `index`, `name` (the image
    /// stem), `time` (s since the start), `strip` and `world_from_rig` (4×4; the rig frame
    /// uses camera axes: x right, y down, z forward).
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for (i, p) in self.model.poses.iter().enumerate() {
            let d = PyDict::new(py);
            d.set_item("index", i)?;
            d.set_item("name", &p.name)?;
            d.set_item("time", p.time)?;
            d.set_item("strip", p.strip)?;
            d.set_item("world_from_rig", matrix(py, &p.world_from_rig)?)?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The rig's cameras as `truth.json` gives them: name, width, height, fx, fy, cx, cy
    /// (pixel centres at +0.5, COLMAP's convention), lens, distortion, port, indices per
    /// channel and `rig_from_camera`.
    #[getter]
    fn cameras<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let water = self.model.ambient_ior();
        let cams: Vec<_> = self
            .model
            .cameras
            .iter()
            .map(|c| poser::truth::camera_truth(c, water))
            .collect();
        to_py(py, &cams)
    }

    /// The resolved model's key numbers for a person (what `poser explain` prints).
    fn explain(&self) -> String {
        poser::explain::explain(&self.model)
    }

    /// The whole resolved model as a dict (what `poser explain --json` prints).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.model)
    }

    /// Project 3D points (metres; an `(N, 3)` array, or one point as `(3,)`, which gives
    /// `N = 1`) through the camera and its port.
    ///
    /// `frame="camera"` (default) or `"world"` at rig pose `pose`. Returns `(uv, status)`:
    /// `uv` an `(N, 2)` float64 array of pixels (centres at +0.5, COLMAP's convention;
    /// OpenCV's = uv − 0.5), NaN where there is no pixel; `status` an `(N,)` array of str:
    /// `"ok"`, `"off_sensor"` (the pixel is still given) or the reason there is no pixel
    /// (`"behind_camera"`, `"inside_glass"`, …). The same numbers as `poser project`.
    #[pyo3(signature = (points, camera = None, frame = "camera", pose = 0, channel = "g"))]
    fn project<'py>(
        &self,
        py: Python<'py>,
        points: PyArrayLikeDyn<'py, f64, numpy::AllowTypeChange>,
        camera: Option<&str>,
        frame: &str,
        pose: usize,
        channel: &str,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
        let ch = poser::optics::project::parse_channel(channel).map_err(PyValueError::new_err)?;
        let cam = self.camera(camera)?;
        let world_pose = match frame {
            "camera" => None,
            "world" => Some(self.pose(pose)?),
            _ => {
                return Err(PyValueError::new_err(format!(
                    "frame `{frame}`: expected \"camera\" or \"world\""
                )));
            }
        };
        let shape = points.shape();
        if !(shape.len() == 2 && shape[1] == 3 || shape == [3]) {
            return Err(PyValueError::new_err(format!(
                "points: expected an (N, 3) array of metres (or one point as (3,)), got \
                 shape {shape:?}"
            )));
        }
        // Row-major logical order whatever the memory layout: x, y, z of each point in turn.
        let flat: Vec<f64> = points.as_array().iter().copied().collect();
        let pts: Vec<glam::DVec3> = flat
            .chunks_exact(3)
            .map(|r| glam::DVec3::new(r[0], r[1], r[2]))
            .collect();
        if let Some(i) = pts.iter().position(|p| !p.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "points[{i}] is not finite: every coordinate must be a finite number of metres"
            )));
        }
        if world_pose.is_some_and(|pi| self.model.above_surface(pi, cam)) {
            return Err(failed(format!(
                "camera `{}` is above the sea surface at pose {pose}: project() projects \
                 through the port only; Scene.truth() projects the targets through the surface",
                self.model.cameras[cam].name
            )));
        }
        let p = self.model.projector(cam, ch).map_err(failed)?;
        let results = py.detach(|| p.project_points(&pts, world_pose));
        let mut uv = Vec::with_capacity(results.len() * 2);
        let mut status = Vec::with_capacity(results.len());
        for r in results {
            match r {
                Ok(px) => {
                    uv.extend_from_slice(&px);
                    status.push(if p.on_sensor(px) { "ok" } else { "off_sensor" }.to_string());
                }
                Err(e) => {
                    uv.extend_from_slice(&[f64::NAN, f64::NAN]);
                    status.push(e.as_str().to_string());
                }
            }
        }
        let n = status.len();
        let uv = uv.into_pyarray(py).reshape([n, 2])?.into_any();
        Ok((uv, strings(py, status)?))
    }

    /// The exact ground truth of every image (what `poser truth` writes as `truth.json`), as
    /// a dict: `scene`, `conventions`, `cameras` (as `Scene.cameras`) and `images`, one dict
    /// per image with `name`, `camera`, `camera_index`, `pose_index`, `world_from_camera` and
    /// `camera_from_world` (`rotation` 3×3, `translation` 3, `quaternion` w, x, y, z) and
    /// `points`: `target`, `id` (str arrays), `uv` (N×2, green), `uv_rgb` (N×3×2, NaN where a
    /// channel has no pixel), `world` and `camera` (N×3, metres).
    fn truth<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let truth = py
            .detach(|| poser::truth::compute(&self.model))
            .map_err(failed)?;
        let pose_dict = |p: &poser::truth::PoseJson| -> PyResult<Bound<'py, PyDict>> {
            let d = PyDict::new(py);
            let rot: Vec<Vec<f64>> = p.rotation.iter().map(|r| r.to_vec()).collect();
            d.set_item("rotation", numpy::PyArray2::from_vec2(py, &rot)?)?;
            d.set_item("translation", PyArray1::from_slice(py, &p.translation))?;
            d.set_item("quaternion", PyArray1::from_slice(py, &p.quaternion))?;
            Ok(d)
        };
        let images = PyList::empty(py);
        for im in &truth.images {
            let d = PyDict::new(py);
            d.set_item("name", &im.name)?;
            d.set_item("camera", &im.camera)?;
            d.set_item("camera_index", im.camera_index)?;
            d.set_item("pose_index", im.pose_index)?;
            d.set_item("world_from_camera", pose_dict(&im.world_from_camera)?)?;
            d.set_item("camera_from_world", pose_dict(&im.camera_from_world)?)?;
            let n = im.points.len();
            let pts = PyDict::new(py);
            let col = |f: &dyn Fn(&poser::truth::Observation) -> String| {
                strings(py, im.points.iter().map(f).collect())
            };
            pts.set_item("target", col(&|o| o.target.clone())?)?;
            pts.set_item("id", col(&|o| o.id.clone())?)?;
            let uv: Vec<f64> = im.points.iter().flat_map(|o| [o.u, o.v]).collect();
            pts.set_item("uv", uv.into_pyarray(py).reshape([n, 2])?)?;
            let uv_rgb: Vec<f64> = im
                .points
                .iter()
                .flat_map(|o| o.uv_rgb.iter().flat_map(|c| c.unwrap_or([f64::NAN; 2])))
                .collect();
            pts.set_item("uv_rgb", uv_rgb.into_pyarray(py).reshape([n, 3, 2])?)?;
            let world: Vec<f64> = im.points.iter().flat_map(|o| o.world.to_array()).collect();
            pts.set_item("world", world.into_pyarray(py).reshape([n, 3])?)?;
            let cam: Vec<f64> = im.points.iter().flat_map(|o| o.camera.to_array()).collect();
            pts.set_item("camera", cam.into_pyarray(py).reshape([n, 3])?)?;
            d.set_item("points", pts)?;
            images.append(d)?;
        }
        let out = PyDict::new(py);
        out.set_item("scene", &truth.scene)?;
        out.set_item("conventions", truth.conventions)?;
        out.set_item("cameras", to_py(py, &truth.cameras)?)?;
        out.set_item("images", images)?;
        Ok(out)
    }

    /// The survey plan: image count, path, time, GSD, overlaps (what `poser plan --json`
    /// gives under `survey`).
    fn plan<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let report = py
            .detach(|| {
                let site = poser::plan::survey::Site::new(&self.model);
                poser::plan::survey::survey(&self.model, &site)
            })
            .map_err(failed)?;
        to_py(py, &report)
    }

    /// The dive plan: profile, decompression, gas and the verdict (what `poser dive --json`
    /// prints).
    fn dive<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let report = py
            .detach(|| {
                poser::plan::dive::plan_dive(&self.model, poser::plan::dive::PROFILE_SAMPLE_EVERY)
            })
            .map_err(failed)?;
        to_py(py, &report)
    }

    /// Render one image with the native renderer: an `(H, W, 3)` float32 array of linear
    /// RGB radiance, row 0 at the top (the bytes `poser render` writes into `<image>.exr`).
    ///
    /// `samples` per pixel (default: the scene's), `scale` a preview factor in (0, 4] of the
    /// camera's resolution (like `--scale`).
    #[pyo3(signature = (pose = 0, camera = None, samples = None, scale = None))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        pose: usize,
        camera: Option<&str>,
        samples: Option<u32>,
        scale: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let pose = self.pose(pose)?;
        let cam = self.camera(camera)?;
        let scaled;
        let model = match scale {
            None => &self.model,
            Some(s) => {
                scaled = self
                    .model
                    .clone()
                    .with_checked_resolution_scale(s)
                    .map_err(PyValueError::new_err)?;
                &scaled
            }
        };
        let img = py
            .detach(|| poser::backend::native::render_one(model, pose, cam, samples))
            .map_err(failed)?;
        let (w, h) = (img.width as usize, img.height as usize);
        let flat: Vec<f32> = img.rgb.into_iter().flatten().collect();
        Ok(flat.into_pyarray(py).reshape([h, w, 3])?.into_any())
    }

    /// Write the scene for another renderer into `out_dir`: `"mitsuba"` (XML) or
    /// `"blender"` (a self-contained bpy script and its `scene.json`), as `poser compile`.
    fn compile(&self, py: Python<'_>, backend: &str, out_dir: PathBuf) -> PyResult<()> {
        let b = Backend::parse(backend).map_err(PyValueError::new_err)?;
        if !b.capabilities().compiles {
            return Err(PyValueError::new_err(
                "the native backend renders directly; use Scene.render() (compile targets: \
                 \"mitsuba\", \"blender\")",
            ));
        }
        py.detach(|| b.compile(&self.model, &out_dir))
            .map_err(failed)
    }

    fn __repr__(&self) -> String {
        format!(
            "<poser.Scene {:?}: {} poses × {} cameras>",
            self.model.name,
            self.model.poses.len(),
            self.model.cameras.len()
        )
    }
}

/// poser: simulate underwater photogrammetry surveys (the compiled module; import `poser`).
#[pymodule]
fn _poser(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("PoserError", py.get_type::<PoserError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<Scene>()?;
    m.add_class::<Diagnostic>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    Ok(())
}
