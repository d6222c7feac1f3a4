//! `Problem`: the algebraic problem, built from a scene (the paper's
//! problems, a scene file: assembled by [`Discretization`], the one the
//! command line solves) or given as it is (an exported instance, one's own
//! matrices, or the problem a study hands to a Python solver), checked by
//! the library's [`ContactProblem::new`] like an imported instance.

use std::sync::Arc;

use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::{Overrides, Scene};
use contactlab::settings::Settings;
use contactlab::solvers::numerics::linalg::{ColumnIndex, SparseRows};
use contactlab::solvers::{ContactNode, ContactProblem, Friction};
use nalgebra_sparse::CsrMatrix;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::{error_of, input_error, interruptible};

/// Where a problem comes from (a clone shares the assembly).
#[derive(Clone)]
pub enum Source {
    /// A scene, with its finest level assembled without the mass matrix M
    /// ([`Discretization::new_without_mass`]).
    Scene {
        scene: Arc<Scene>,
        finest: Arc<Discretization>,
    },
    /// An algebraic problem alone (no mesh).
    Algebraic(Arc<ContactProblem>),
}

/// A problem and the settings it brings (a scene file's).
#[pyclass(frozen, module = "contactlab._contactlab")]
pub struct Problem {
    pub name: String,
    pub source: Source,
    pub settings: Settings,
}

impl Problem {
    /// An algebraic problem given as it is (what a study hands a Python
    /// solver).
    pub fn of_algebraic(problem: ContactProblem) -> Self {
        Self {
            name: "algebraic problem".into(),
            source: Source::Algebraic(Arc::new(problem)),
            settings: Settings::default(),
        }
    }

    /// The problem as the Python layer's `contactlab.Problem`.
    pub fn wrapped<'py>(self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let inner = Bound::new(py, self)?;
        py.import("contactlab")?.getattr("Problem")?.call1((inner,))
    }

    /// The algebraic problem (the finest level's, for a scene).
    pub fn algebraic(&self) -> &ContactProblem {
        match &self.source {
            Source::Scene { finest, .. } => &finest.problem,
            Source::Algebraic(p) => p,
        }
    }

    /// The scene and its finest level, or an error that says why a problem
    /// given by its matrices cannot do `what`.
    pub fn scene(&self, what: &str) -> PyResult<(&Arc<Scene>, &Arc<Discretization>)> {
        match &self.source {
            Source::Scene { scene, finest } => Ok((scene, finest)),
            Source::Algebraic(_) => Err(input_error(format!(
                "{what} needs a problem built from a scene (Problem.paper or Problem.from_scene): \
                 this one was given by its matrices, without the mesh its studies assemble"
            ))),
        }
    }

    /// A friction bound given from Python: one finite value ≥ 0 per
    /// contact node, checked as a solve checks it.
    pub fn bound_checked(&self, g: &[f64]) -> PyResult<()> {
        Friction::Given(g)
            .check(self.algebraic())
            .map_err(|m| input_error(format!("bound: {m}")))
    }
}

/// The scene with the overrides of `solve --problem/--scene`, applied by
/// the library's [`Overrides`] (as the command line does), and assembled
/// (interruptibly, and refused up front if it would not fit in memory).
#[allow(clippy::too_many_arguments)]
fn build(
    py: Python<'_>,
    scene: Scene,
    settings: Settings,
    h: Option<&str>,
    young: Option<f64>,
    poisson: Option<f64>,
    plane: Option<&str>,
    friction: Option<f64>,
) -> PyResult<Problem> {
    let h = h
        .map(|h| {
            h.parse::<MeshSize>()
                .map_err(|m| input_error(format!("h: {m}")))
        })
        .transpose()?;
    let plane = plane
        .map(|p| {
            use contactlab::mechanics::material::PlaneModel;
            PlaneModel::ALL
                .into_iter()
                .find(|m| m.name() == p.trim())
                .ok_or_else(|| input_error(format!("plane = '{p}': give 'strain' or 'stress'")))
        })
        .transpose()?;
    let overrides = Overrides {
        h,
        young,
        poisson,
        plane,
        friction,
    };
    let scene = overrides.apply(scene).map_err(input_error)?;
    // Without the mass matrix M, which only the relaxation's proximal term
    // reads (it assembles its own level) and `M` and `export` assemble on
    // demand: M is a third of the level (the problem alone peaked at 5.66
    // GiB at h = 1/4096 with it).
    let (scene, finest) = interruptible(py, move |_| {
        let finest = Discretization::new_without_mass(&scene, scene.finest())?;
        Ok((scene, finest))
    })?;
    Ok(Problem {
        name: scene.name.clone(),
        source: Source::Scene {
            scene: Arc::new(scene),
            finest: Arc::new(finest),
        },
        settings,
    })
}

/// A sparse matrix as numpy arrays: (indptr, indices, data).
type Csr<'py> = (
    Bound<'py, PyArray1<usize>>,
    Bound<'py, PyArray1<usize>>,
    Bound<'py, PyArray1<f64>>,
);

fn csr<'py, A: SparseRows>(py: Python<'py>, a: &A) -> Csr<'py> {
    let cols: Vec<usize> = (0..a.nrows())
        .flat_map(|i| {
            let (lo, hi) = a.row_range(i);
            a.row_columns(i, lo, hi).iter()
        })
        .collect();
    let offsets: Vec<usize> = a.row_offsets().iter().map(|o| o.at()).collect();
    (
        offsets.into_pyarray(py),
        cols.into_pyarray(py),
        a.values().to_vec(a.row_offsets()).into_pyarray(py),
    )
}

/// A CSR matrix from Python's canonical (indptr, indices, data) of shape
/// (rows, cols), checked before it is built.
fn csr_in(
    name: &str,
    (rows, cols): (usize, usize),
    (indptr, indices, data): (Vec<usize>, Vec<usize>, Vec<f64>),
) -> PyResult<CsrMatrix<f64>> {
    CsrMatrix::try_from_csr_data(rows, cols, indptr, indices, data)
        .map_err(|e| input_error(format!("{name}: {e}")))
}

type CsrIn = (Vec<usize>, Vec<usize>, Vec<f64>);

#[pymethods]
impl Problem {
    /// The paper's problem `number` (1, 2 or 3).
    #[staticmethod]
    #[pyo3(signature = (number, h=None, young=None, poisson=None, plane=None, friction=None))]
    fn paper(
        py: Python<'_>,
        number: i64,
        h: Option<&str>,
        young: Option<f64>,
        poisson: Option<f64>,
        plane: Option<&str>,
        friction: Option<f64>,
    ) -> PyResult<Self> {
        let number = u32::try_from(number).map_err(|_| {
            input_error(format!(
                "number = {number}: give the paper's problem 1, 2 or 3"
            ))
        })?;
        let scene = Scene::paper_problem(number).map_err(input_error)?;
        build(
            py,
            scene,
            Settings::default(),
            h,
            young,
            poisson,
            plane,
            friction,
        )
    }

    /// A scene file (TOML, as `solve --scene` reads it), with the settings
    /// it brings: every solve of the problem starts from them, as the
    /// command line's does.
    #[staticmethod]
    #[pyo3(signature = (path, h=None, young=None, poisson=None, plane=None, friction=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_scene(
        py: Python<'_>,
        path: std::path::PathBuf,
        h: Option<&str>,
        young: Option<f64>,
        poisson: Option<f64>,
        plane: Option<&str>,
        friction: Option<f64>,
    ) -> PyResult<Self> {
        let (scene, settings) =
            contactlab::formats::scene_file::load(&path).map_err(|e| error_of(e.into()))?;
        build(py, scene, settings, h, young, poisson, plane, friction)
    }

    /// A folder written by `contactlab export` (or `Problem.export`), read
    /// back with every file held to what `problem.json` declares.
    #[staticmethod]
    fn from_instance(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Self> {
        let name = format!("instance {}", path.display());
        let instance = interruptible(py, move |_| contactlab::formats::instance::import(&path))?;
        Ok(Self {
            name,
            source: Source::Algebraic(Arc::new(instance.problem)),
            settings: Settings::default(),
        })
    }

    /// A problem from its matrices: A (n × n, symmetric positive
    /// semidefinite), f, M (optional), the contact nodes (t, s, weight,
    /// coefficient per node, and optionally the initial gap d ≥ 0: t ≤ d,
    /// and the slip offset σ: friction on s − σ), the rigid modes (n each, A z = 0) and the
    /// prolongations of a nested hierarchy (coarse to fine, optional), each
    /// checked as an imported instance is.
    #[staticmethod]
    #[pyo3(signature = (name, n, a, f, t, s, weight, coefficient, rigid_modes, m=None, prolongations=Vec::new(), gap=None, slip_offset=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_matrices(
        name: String,
        n: usize,
        a: CsrIn,
        f: Vec<f64>,
        t: Vec<usize>,
        s: Vec<usize>,
        weight: Vec<f64>,
        coefficient: Vec<f64>,
        rigid_modes: Vec<Vec<f64>>,
        m: Option<CsrIn>,
        prolongations: Vec<((usize, usize), CsrIn)>,
        gap: Option<Vec<f64>>,
        slip_offset: Option<Vec<f64>>,
    ) -> PyResult<Self> {
        let a = csr_in("A", (n, n), a)?;
        let k = t.len();
        if s.len() != k || weight.len() != k || coefficient.len() != k {
            return Err(input_error(format!(
                "contact: t has {k} nodes, s {}, weight {}, coefficient {}: give one of each per node",
                s.len(),
                weight.len(),
                coefficient.len()
            )));
        }
        let contacts: Vec<ContactNode> = (0..k)
            .map(|i| ContactNode {
                t: t[i],
                s: s[i],
                weight: weight[i],
                coefficient: coefficient[i],
            })
            .collect();
        let mass = match m {
            Some(m) => contactlab::solvers::Mass::Matrix(csr_in("M", (n, n), m)?),
            None => contactlab::solvers::Mass::Omitted,
        };
        let mut problem = ContactProblem::new(a, f, mass, contacts, rigid_modes)
            .and_then(|p| match gap {
                Some(gap) => p.with_gap(gap),
                None => Ok(p),
            })
            .and_then(|p| match slip_offset {
                Some(offset) => p.with_slip_offset(offset),
                None => Ok(p),
            })
            .map_err(|e| input_error(e.to_string()))?;
        contactlab::certificate::problem_checks::check_definite(
            &problem,
            contactlab::certificate::bound_room(),
        )
        .map_err(input_error)?;
        if !prolongations.is_empty() {
            let ps = prolongations
                .into_iter()
                .enumerate()
                .map(|(l, (shape, p))| csr_in(&format!("prolongations[{l}]"), shape, p))
                .collect::<PyResult<Vec<_>>>()?;
            problem = problem
                .with_hierarchy(ps)
                .map_err(|e| input_error(format!("prolongations: {e}")))?;
        }
        Ok(Self {
            name,
            source: Source::Algebraic(Arc::new(problem)),
            settings: Settings::default(),
        })
    }

    #[getter]
    fn name(&self) -> String {
        self.name.clone()
    }

    /// The mesh size, as the command line writes it ("1/64"); None for a
    /// problem given by its matrices.
    #[getter]
    fn h(&self) -> Option<String> {
        match &self.source {
            Source::Scene { finest, .. } => Some(finest.h().to_string()),
            Source::Algebraic(_) => None,
        }
    }

    #[getter]
    fn n(&self) -> usize {
        self.algebraic().n()
    }

    /// A in CSR: (indptr, indices, data).
    fn _a<'py>(&self, py: Python<'py>) -> Csr<'py> {
        csr(py, self.algebraic().a())
    }

    /// M, the mass matrix of the proximal term, in CSR: given, or for a
    /// scene assembled from its mesh now (the problem does not keep it).
    fn _m<'py>(&self, py: Python<'py>) -> PyResult<Csr<'py>> {
        match &self.source {
            Source::Scene { finest, .. } => {
                let finest = finest.clone();
                let m = interruptible(py, move |_| Ok(finest.assemble_mass()?))?;
                Ok(csr(py, &m))
            }
            Source::Algebraic(p) => {
                let m = p.mass().ok_or_else(|| {
                    input_error("this problem was given without its mass matrix M")
                })?;
                Ok(csr(py, &*m))
            }
        }
    }

    #[getter]
    fn f<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.algebraic().f().to_vec().into_pyarray(py)
    }

    /// The contact nodes: t, s (indices of the jump and slip unknowns),
    /// weight, coefficient (𝓕) and x (None without a mesh), each an array.
    fn _contact<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.algebraic().contacts();
        let d = PyDict::new(py);
        let column = |f: fn(&ContactNode) -> f64| c.iter().map(f).collect::<Vec<_>>();
        d.set_item(
            "t",
            c.iter().map(|c| c.t).collect::<Vec<_>>().into_pyarray(py),
        )?;
        d.set_item(
            "s",
            c.iter().map(|c| c.s).collect::<Vec<_>>().into_pyarray(py),
        )?;
        d.set_item("weight", column(|c| c.weight).into_pyarray(py))?;
        d.set_item("coefficient", column(|c| c.coefficient).into_pyarray(py))?;
        match &self.source {
            Source::Scene { finest, .. } => d.set_item("x", finest.contact_x().into_pyarray(py))?,
            Source::Algebraic(_) => d.set_item("x", py.None())?,
        }
        Ok(d)
    }

    /// The problem's own scales (force, contact load, length of Γ_K,
    /// stiffness, pressure P, displacement U): what the certificate and the
    /// comparisons measure in.
    #[getter]
    fn scales<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.algebraic().scales();
        let d = PyDict::new(py);
        for (name, value) in [
            ("force", s.force),
            ("contact_load", s.contact_load),
            ("length", s.length),
            ("stiffness", s.stiffness),
            ("pressure", s.pressure),
            ("displacement", s.displacement),
        ] {
            d.set_item(name, value)?;
        }
        Ok(d)
    }

    /// The rigid mode: for a scene, the upper body's vertical translation
    /// in the unknowns (A's kernel); else the first one given.
    #[getter]
    fn rigid_mode<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        match &self.source {
            Source::Scene { finest, .. } => finest.kernel_vector().into_pyarray(py),
            Source::Algebraic(p) => p.rigid_modes()[0].clone().into_pyarray(py),
        }
    }

    /// The number of levels of its hierarchy (0: none; multigrid solvers
    /// need one above 256 unknowns).
    #[getter]
    fn levels(&self) -> usize {
        self.algebraic().prolongations().len()
    }

    fn __repr__(&self) -> String {
        let cp = self.algebraic();
        match &self.source {
            Source::Scene { finest, .. } => format!(
                "Problem({}, h = {}, {} unknowns, {} contact nodes)",
                self.name,
                finest.h(),
                cp.n(),
                cp.contacts().len()
            ),
            Source::Algebraic(_) => format!(
                "Problem({}, {} unknowns, {} contact nodes)",
                self.name,
                cp.n(),
                cp.contacts().len()
            ),
        }
    }
}

/// A real array given from Python, as a vector.
pub fn vector(a: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<f64>> {
    Ok(a.as_slice()
        .map_err(|e| input_error(e.to_string()))?
        .to_vec())
}
