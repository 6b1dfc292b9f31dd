//! Bindings of the linalg kernels (covariance, eigh, k-means).
//!
//! Each function checks its Python arguments (ndarray, dtype float64, number of dimensions; a
//! copy when an array is not C-contiguous), runs the pure kernel with the GIL released (inside
//! an optional local rayon pool of `n_threads` threads) and hands the kernel's buffers to numpy
//! without copying. Value checks (empty input, NaN/inf, k out of range, asymmetry) live in the
//! kernels and come back as `ValueError`.

use std::borrow::Cow;

use numpy::ndarray::Array2;
use numpy::{
    IntoPyArray, PyArray1, PyArray2, PyArrayDescrMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use super::args::{n_threads_arg, opt_usize_in, Int, Real};
use super::arrays::{check_dtype, f64_values, ndarray_or, shape_str, F64Array};
use crate::buffer::try_copy;
use crate::covariance::Moments;
use crate::kmeans::{self as km, KMeansParams};
use crate::kmeanspp::{self, Rng};
use crate::{covariance as cov, eigh as eig};

/// `(vector, matrix)` results.
type VecMat<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray2<f64>>);

/// Labels or row indices.
type LabelsArray<'py> = Bound<'py, PyArray1<i64>>;

/// A read-only 2-D float64 array argument.
struct Matrix<'py> {
    array: F64Array<'py>,
    rows: usize,
    cols: usize,
}

impl Matrix<'_> {
    /// Row-major values: borrowed when the array is C-contiguous, copied otherwise.
    fn values(&self) -> Cow<'_, [f64]> {
        self.array.values()
    }
}

/// A numpy array of a real dtype other than float64 (bool, integers, floats) converted with
/// ``astype(numpy.float64)``; anything else unchanged (then checked by [`matrix`]).
fn real_as_f64<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    if let Ok(arr) = obj.cast::<PyUntypedArray>() {
        let dtype = arr.dtype();
        if !dtype.is_equiv_to(&numpy::dtype::<f64>(obj.py())) && b"biuf".contains(&dtype.kind()) {
            return obj.call_method1("astype", ("float64",));
        }
    }
    Ok(obj.clone())
}

/// `obj` as a 2-D float64 numpy array; `what` describes the expected content.
fn matrix<'py>(obj: &Bound<'py, PyAny>, name: &str, what: &str) -> PyResult<Matrix<'py>> {
    let arr = ndarray_or(obj, |ty| {
        format!("{name} must be a 2-D numpy.ndarray of float64 ({what}), got {ty}")
    })?;
    check_dtype::<f64>(arr, name, "float64")?;
    if arr.ndim() != 2 {
        return Err(PyValueError::new_err(format!(
            "{name} must be 2-D ({what}), got {} dimension(s) with shape {}",
            arr.ndim(),
            shape_str(arr.shape())
        )));
    }
    let (rows, cols) = (arr.shape()[0], arr.shape()[1]);
    let array = f64_values(arr)?;
    Ok(Matrix { array, rows, cols })
}

/// Run `f` in a local pool of `n_threads` threads (`None`: rayon's global pool).
fn in_pool<T: Send>(n_threads: Option<usize>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    match n_threads {
        None => Ok(f()),
        Some(t) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(t)
                .build()
                .map_err(|e| PyValueError::new_err(format!("cannot start {t} threads: {e}")))?;
            Ok(pool.install(f))
        }
    }
}

fn seed_arg(obj: &Bound<'_, PyAny>) -> PyResult<u64> {
    obj.extract::<u64>().map_err(|_| {
        PyValueError::new_err(format!(
            "seed must be an integer in [0, 2**64), got {}",
            obj.repr()
                .map(|r| r.to_string())
                .unwrap_or_else(|_| "?".into())
        ))
    })
}

fn square<'py>(
    py: Python<'py>,
    v: Vec<f64>,
    rows: usize,
    cols: usize,
) -> Bound<'py, PyArray2<f64>> {
    Array2::from_shape_vec((rows, cols), v)
        .expect("kernel output has the announced shape")
        .into_pyarray(py)
}

/// Mean ``(d,)`` and covariance ``(d, d)`` with divisor N of the rows of ``x`` ``(N, d)``.
#[pyfunction]
#[pyo3(signature = (x, *, n_threads=None))]
fn covariance<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    n_threads: Option<Int>,
) -> PyResult<VecMat<'py>> {
    let n_threads = n_threads_arg(n_threads)?;
    let m = matrix(x, "X", "rows are observations")?;
    let (n, d) = (m.rows, m.cols);
    let values = m.values();
    let data: &[f64] = &values;
    let (mean, c) = py.detach(|| in_pool(n_threads, || cov::covariance(data, n, d)))??;
    Ok((mean.into_pyarray(py), square(py, c, d, d)))
}

/// Mergeable (count, mean, scatter) of a stream of row blocks.
///
/// ``acc.update(X)`` adds the rows of an ``(n, d)`` float64 block (``n = 0`` allowed);
/// ``acc.merge(other)`` adds another accumulator (Chan, Golub & LeVeque's pairwise update), so
/// a corpus can be reduced chunk by chunk or in parallel pieces. ``acc.mean`` ``(d,)``,
/// ``acc.scatter`` ``(d, d)`` (``Σ (x - mean)(x - mean)ᵀ``) and ``acc.covariance()`` (divisor
/// N) equal the one-shot :func:`covariance` of all rows within 1e-9 relative; ``acc.count`` is
/// the number of rows, ``acc.dim`` their dimension (fixed by ``CovarianceAccumulator(dim)`` or
/// the first update). Accumulators pickle. Reading ``mean``/``scatter``/``covariance()``
/// before any row raises ValueError, as does a block or accumulator of another dimension.
#[pyclass(name = "CovarianceAccumulator", module = "visprim._visprim")]
struct CovarianceAccumulator {
    inner: Option<Moments>,
}

impl CovarianceAccumulator {
    fn dim_mismatch(&self, d: usize, what: &str) -> PyResult<()> {
        match &self.inner {
            Some(m) if m.dim() != d => Err(PyValueError::new_err(format!(
                "{what} has {d} columns but the accumulator holds rows of dimension {}",
                m.dim()
            ))),
            _ => Ok(()),
        }
    }
}

#[pymethods]
impl CovarianceAccumulator {
    #[new]
    #[pyo3(signature = (dim=None))]
    fn new(dim: Option<Int>) -> PyResult<Self> {
        let dim = opt_usize_in(dim, "dim", 1, usize::MAX, "the dimension of the rows")?;
        Ok(Self {
            inner: dim.map(Moments::new).transpose()?,
        })
    }

    /// Add the rows of ``x`` ``(n, d)``; ``n = 0`` is allowed and changes nothing. An array of
    /// another real dtype (bool, integers, floats) is converted to float64 first.
    #[pyo3(signature = (x, *, n_threads=None))]
    fn update(
        &mut self,
        py: Python<'_>,
        x: &Bound<'_, PyAny>,
        n_threads: Option<Int>,
    ) -> PyResult<()> {
        let n_threads = n_threads_arg(n_threads)?;
        let x = real_as_f64(x)?;
        let m = matrix(&x, "X", "rows are observations")?;
        let (n, d) = (m.rows, m.cols);
        if d == 0 {
            return Err(PyValueError::new_err(format!(
                "X has shape ({n}, 0): rows need at least one column"
            )));
        }
        self.dim_mismatch(d, "X")?;
        let values = m.values();
        let data: &[f64] = &values;
        let block = py.detach(|| in_pool(n_threads, || Moments::from_rows(data, n, d)))??;
        match &mut self.inner {
            Some(acc) => acc.merge(&block)?,
            None => self.inner = Some(block),
        }
        Ok(())
    }

    /// Add the statistics of another accumulator (``other`` is unchanged; ``acc.merge(acc)``
    /// merges a copy, doubling every row's weight).
    fn merge(slf: &Bound<'_, Self>, other: &Bound<'_, Self>) -> PyResult<()> {
        if slf.is(other) {
            let copy = slf
                .try_borrow()?
                .inner
                .as_ref()
                .map(Moments::try_clone)
                .transpose()?;
            return slf.try_borrow_mut()?.merge_moments(copy.as_ref());
        }
        let theirs = other.try_borrow()?;
        slf.try_borrow_mut()?.merge_moments(theirs.inner.as_ref())
    }

    /// Number of rows seen.
    #[getter]
    fn count(&self) -> u64 {
        self.inner.as_ref().map_or(0, |m| m.count())
    }

    /// Dimension of the rows (``None`` until the first update if not given).
    #[getter]
    fn dim(&self) -> Option<usize> {
        self.inner.as_ref().map(|m| m.dim())
    }

    /// Mean of the rows seen, ``(d,)`` (a copy).
    #[getter]
    fn mean<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let m = self.nonempty()?;
        Ok(try_copy(m.mean(), "the mean")?.into_pyarray(py))
    }

    /// Scatter matrix ``Σ (x - mean)(x - mean)ᵀ``, ``(d, d)`` (a copy).
    #[getter]
    fn scatter<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = self.nonempty()?;
        let scatter = try_copy(m.scatter(), "the scatter matrix")?;
        Ok(square(py, scatter, m.dim(), m.dim()))
    }

    /// Covariance with divisor N, ``(d, d)``.
    fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let m = self.nonempty()?;
        Ok(square(py, m.covariance()?, m.dim(), m.dim()))
    }

    fn __repr__(&self) -> String {
        match &self.inner {
            None => "CovarianceAccumulator(dim=None, count=0)".into(),
            Some(m) => format!(
                "CovarianceAccumulator(dim={}, count={})",
                m.dim(),
                m.count()
            ),
        }
    }

    fn __getstate__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        match &self.inner {
            None => PyTuple::new(py, [py.None()]),
            Some(m) => (
                m.dim(),
                m.count(),
                try_copy(m.mean(), "the mean")?.into_pyarray(py),
                try_copy(m.scatter(), "the scatter matrix")?.into_pyarray(py),
            )
                .into_pyobject(py),
        }
    }

    fn __setstate__(&mut self, state: &Bound<'_, PyTuple>) -> PyResult<()> {
        if state.len() == 1 {
            self.inner = None;
            return Ok(());
        }
        let (dim, count, mean, scatter): (Int, Int, Vec<f64>, Vec<f64>) = state.extract()?;
        let dim = dim.usize_in("dim", 1, usize::MAX, "the dimension of the rows")?;
        let count = count.in_range("count", 0, i64::MAX, "the number of rows")? as u64;
        self.inner = Some(Moments::from_parts(dim, count, mean, scatter)?);
        Ok(())
    }
}

impl CovarianceAccumulator {
    /// Add `other`'s statistics (nothing for `None`).
    fn merge_moments(&mut self, other: Option<&Moments>) -> PyResult<()> {
        let Some(o) = other else { return Ok(()) };
        self.dim_mismatch(o.dim(), "other")?;
        match &mut self.inner {
            Some(acc) => acc.merge(o)?,
            None => self.inner = Some(o.try_clone()?),
        }
        Ok(())
    }

    fn nonempty(&self) -> PyResult<&Moments> {
        match &self.inner {
            Some(m) if m.count() > 0 => Ok(m),
            _ => Err(PyValueError::new_err(
                "the accumulator has seen no rows yet; call update(X) first",
            )),
        }
    }
}

/// Eigenvalues (descending) and eigenvectors (columns) of the symmetric matrix ``a``.
#[pyfunction]
#[pyo3(signature = (a, *, k=None))]
fn eigh<'py>(py: Python<'py>, a: &Bound<'py, PyAny>, k: Option<Int>) -> PyResult<VecMat<'py>> {
    let k = opt_usize_in(k, "k", 1, usize::MAX, "leading eigenpairs to return")?;
    let m = matrix(a, "K", "a symmetric matrix")?;
    if m.rows != m.cols {
        return Err(PyValueError::new_err(format!(
            "K must be square, got shape ({}, {})",
            m.rows, m.cols
        )));
    }
    let d = m.rows;
    let values = m.values();
    let data: &[f64] = &values;
    let e = py.detach(|| eig::eigh(data, d, k))?;
    let kk = e.values.len();
    Ok((e.values.into_pyarray(py), square(py, e.vectors, d, kk)))
}

/// A k-means clustering (see :func:`visprim.kernels.kmeans`): ``centers`` ``(k, d)`` float64,
/// ``labels`` ``(N,)`` int64 (index of each row's centre), ``inertia`` (sum of squared
/// distances of the rows to their centre, in squared units of ``X``) and ``n_iter`` (Lloyd
/// iterations of the best run).
#[pyclass(name = "KMeansResult", module = "visprim._visprim", frozen)]
struct KMeansResult {
    centers: Py<PyArray2<f64>>,
    labels: Py<PyArray1<i64>>,
    #[pyo3(get)]
    inertia: f64,
    #[pyo3(get)]
    n_iter: usize,
}

#[pymethods]
impl KMeansResult {
    /// Cluster centres, ``(k, d)``.
    #[getter]
    fn centers(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.centers.clone_ref(py)
    }

    /// Cluster of each row of ``X``, ``(N,)`` int64.
    #[getter]
    fn labels(&self, py: Python<'_>) -> Py<PyArray1<i64>> {
        self.labels.clone_ref(py)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let shape = self.centers.bind(py).shape().to_vec();
        format!(
            "KMeansResult(k={}, d={}, inertia={}, n_iter={})",
            shape[0], shape[1], self.inertia, self.n_iter
        )
    }
}

fn local_trials_arg(n_local_trials: Option<Int>) -> PyResult<Option<usize>> {
    opt_usize_in(
        n_local_trials,
        "n_local_trials",
        1,
        kmeanspp::MAX_LOCAL_TRIALS,
        "candidates per seeding step",
    )
}

fn labels_i64(labels: Vec<u32>) -> Vec<i64> {
    labels.into_iter().map(i64::from).collect()
}

/// k-means++ seeding then Lloyd iterations, best of ``n_init`` runs.
#[pyfunction]
#[pyo3(signature = (
    x, k, *, n_init=Int::Small(1), max_iter=Int::Small(300), tol=Real(1e-4), seed=None,
    init=None, n_local_trials=None, n_threads=None
))]
#[allow(clippy::too_many_arguments)]
fn kmeans(
    py: Python<'_>,
    x: &Bound<'_, PyAny>,
    k: Int,
    n_init: Int,
    max_iter: Int,
    tol: Real,
    seed: Option<&Bound<'_, PyAny>>,
    init: Option<&Bound<'_, PyAny>>,
    n_local_trials: Option<Int>,
    n_threads: Option<Int>,
) -> PyResult<KMeansResult> {
    let k = k.usize_in("k", 1, usize::MAX, "the number of clusters")?;
    let n_init = n_init.usize_in("n_init", 1, usize::MAX, "independent seedings")?;
    let max_iter = max_iter.usize_in("max_iter", 1, usize::MAX, "Lloyd iterations per run")?;
    let tol = tol.0;
    let n_local_trials = local_trials_arg(n_local_trials)?;
    let n_threads = n_threads_arg(n_threads)?;
    let m = matrix(x, "X", "rows are observations")?;
    let (n, d) = (m.rows, m.cols);
    let seed = seed.map(seed_arg).transpose()?.unwrap_or(0);
    let init = init
        .map(|i| matrix(i, "init", "initial centres, one per row"))
        .transpose()?;
    if let Some(i) = &init {
        if i.rows != k || i.cols != d {
            return Err(PyValueError::new_err(format!(
                "init must have shape (k, d) = ({k}, {d}), got ({}, {})",
                i.rows, i.cols
            )));
        }
    }
    let params = KMeansParams {
        k,
        n_init,
        max_iter,
        tol,
        seed,
        n_local_trials,
    };
    let values = m.values();
    let data: &[f64] = &values;
    let init_values = init.as_ref().map(|i| i.values());
    let init_data: Option<&[f64]> = init_values.as_deref();
    let r = py.detach(|| in_pool(n_threads, || km::kmeans(data, n, d, &params, init_data)))??;
    Ok(KMeansResult {
        centers: square(py, r.centers, k, d).unbind(),
        labels: labels_i64(r.labels).into_pyarray(py).unbind(),
        inertia: r.inertia,
        n_iter: r.n_iter,
    })
}

/// Nearest centre and Euclidean distance to it for every row of ``x``.
#[pyfunction]
#[pyo3(signature = (x, centers, *, n_threads=None))]
fn kmeans_predict<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    centers: &Bound<'py, PyAny>,
    n_threads: Option<Int>,
) -> PyResult<(LabelsArray<'py>, Bound<'py, PyArray1<f64>>)> {
    let n_threads = n_threads_arg(n_threads)?;
    let m = matrix(x, "X", "rows are observations")?;
    let c = matrix(centers, "centers", "one centre per row")?;
    if c.cols != m.cols {
        return Err(PyValueError::new_err(format!(
            "X has {} columns but centers has {}",
            m.cols, c.cols
        )));
    }
    let (n, d, k) = (m.rows, m.cols, c.rows);
    let (xv, cv) = (m.values(), c.values());
    let (xd, cd): (&[f64], &[f64]) = (&xv, &cv);
    let (labels, sq) = py.detach(|| in_pool(n_threads, || km::predict(xd, n, d, cd, k)))??;
    let dist: Vec<f64> = sq.into_iter().map(f64::sqrt).collect();
    Ok((labels_i64(labels).into_pyarray(py), dist.into_pyarray(py)))
}

/// Greedy k-means++ seeds: ``(centers (k, d), row indices (k,) int64)``.
#[pyfunction]
#[pyo3(signature = (x, k, *, seed=None, n_local_trials=None, n_threads=None))]
fn kmeans_plusplus<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    k: Int,
    seed: Option<&Bound<'py, PyAny>>,
    n_local_trials: Option<Int>,
    n_threads: Option<Int>,
) -> PyResult<(Bound<'py, PyArray2<f64>>, LabelsArray<'py>)> {
    let k = k.usize_in("k", 1, usize::MAX, "the number of seeds")?;
    let n_local_trials = local_trials_arg(n_local_trials)?;
    let n_threads = n_threads_arg(n_threads)?;
    let m = matrix(x, "X", "rows are observations")?;
    let (n, d) = (m.rows, m.cols);
    let seed = seed.map(seed_arg).transpose()?.unwrap_or(0);
    let values = m.values();
    let data: &[f64] = &values;
    let (centers, idx) = py.detach(|| {
        in_pool(n_threads, || -> crate::Result<(Vec<f64>, Vec<usize>)> {
            crate::simd::level()?;
            km::data_stats(data, n, d, "X")?;
            let trials = n_local_trials.unwrap_or_else(|| kmeanspp::default_local_trials(k));
            km::check_k_and_trials(k, n, trials)?;
            Ok(kmeanspp::kmeans_plusplus(
                data,
                n,
                d,
                k,
                trials,
                &mut Rng::new(seed),
            ))
        })
    })??;
    let idx: Vec<i64> = idx.into_iter().map(|i| i as i64).collect();
    Ok((square(py, centers, k, d), idx.into_pyarray(py)))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(covariance, m)?)?;
    m.add_class::<CovarianceAccumulator>()?;
    m.add_function(wrap_pyfunction!(eigh, m)?)?;
    m.add_class::<KMeansResult>()?;
    m.add_function(wrap_pyfunction!(kmeans, m)?)?;
    m.add_function(wrap_pyfunction!(kmeans_predict, m)?)?;
    m.add_function(wrap_pyfunction!(kmeans_plusplus, m)?)?;
    Ok(())
}
