/* The per-call entries of the flat layer that run in a few microseconds, as C functions
 * with CPython's vectorcall convention (METH_FASTCALL), for the calls where f2py's
 * generic wrapper is a sizeable part of the call: conmech.Propagator.propagate_until
 * (flat_propagation_until) and solve_ivp's fast entry for small systems
 * (flat_propagation_solve). Each function takes the arguments of the f2py wrapper of the
 * same Fortran routine, positionally and with the same hidden sizes taken from the
 * arrays, and calls that routine: the same numbers in, the same numbers out.
 *
 * f2py's wrapper parses keywords, builds or checks a numpy array per array argument
 * (converting or copying when it must) and a return value; here the arguments' kinds are
 * checked with type and flag tests only (no conversion, no copy: an argument of another
 * kind is refused with a TypeError or ValueError that names it; the callers pass arrays
 * of exactly these kinds). A read-only argument may also be a list or tuple of floats and
 * ints (a state, output times), read into a buffer, or a strided or byte-swapped float64
 * array, copied.
 *
 * The functions are compiled into the extension module conmech._conmech and are a module
 * of their own, conmech._fastcall, with its own init function in the same shared object
 * (conmech._core.fastcall loads it from _conmech's file): one copy of the Fortran
 * library, so that a propagation made through f2py's flat_propagation_new is the one
 * these calls run.
 *
 * The Fortran routines are external procedures compiled by gfortran: their names are the
 * lower-case name with one trailing underscore, and every argument is passed by reference
 * (integer(c_int) as int, integer(c_int64_t) as int64_t, real(c_double) as double, the
 * explicit-shape arrays as pointers to their first element), as f2py's own wrapper calls
 * them. As f2py's wrapper, the calls hold the GIL (the routines call no Python). */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <limits.h>
#include <stdint.h>
#define NPY_NO_DEPRECATED_API NPY_1_7_API_VERSION
#include <numpy/arrayobject.h>

extern void flat_propagation_until_(int64_t *handle, int *lp, double *params, double *t0,
                                    double *t1, int *n, double *y, int64_t *iout);
extern void flat_propagation_solve_(int64_t *handle, int *lp, double *params, double *t0,
                                    double *tf, int *n, double *y0, double *h0, double *hmax,
                                    int *max_steps, int *with_t_eval, int *neval, int *lt,
                                    double *t_eval, int *nout, double *out, int64_t *iout);

/* the length of iout in every flat routine: 8 numbers, then the message's 256 bytes */
#define IOUT_SIZE 40
/* states and output times given as lists up to this size are read into the stack */
#define STACK_DOUBLES 64

/* The data of a one-dimensional, C-contiguous, aligned numpy array of type `type` in the
 * machine's byte order (writeable when `writeable`) and its size in *size (at most
 * INT_MAX: the Fortran routines take sizes as int); NULL with a TypeError or ValueError
 * naming the argument `name` otherwise. */
static void *array_data(PyObject *obj, int type, int writeable, const char *name,
                        int *size)
{
    PyArrayObject *a;
    if (!PyArray_Check(obj)) {
        PyErr_Format(PyExc_TypeError, "%s must be a numpy array, got %.100s", name,
                     Py_TYPE(obj)->tp_name);
        return NULL;
    }
    a = (PyArrayObject *)obj;
    if (PyArray_TYPE(a) != type) {
        PyErr_Format(PyExc_TypeError, "%s must be an array of %s", name,
                     type == NPY_DOUBLE ? "float64" : "int64");
        return NULL;
    }
    if (PyArray_NDIM(a) != 1 || !PyArray_IS_C_CONTIGUOUS(a) || !PyArray_ISALIGNED(a)) {
        PyErr_Format(PyExc_ValueError, "%s must be a one-dimensional contiguous array",
                     name);
        return NULL;
    }
    if (!PyArray_ISNOTSWAPPED(a)) {
        PyErr_Format(PyExc_ValueError, "%s must be in the machine's byte order", name);
        return NULL;
    }
    if (writeable && !PyArray_ISWRITEABLE(a)) {
        PyErr_Format(PyExc_ValueError, "%s must be writeable", name);
        return NULL;
    }
    if (PyArray_DIM(a, 0) > INT_MAX) {
        PyErr_Format(PyExc_ValueError, "%s has more than %d entries", name, INT_MAX);
        return NULL;
    }
    *size = (int)PyArray_DIM(a, 0);
    return PyArray_DATA(a);
}

/* A sequence of numbers to read: a float64 array's data (or a contiguous copy's, owned),
 * or a list or tuple read into `stack` (its first STACK_DOUBLES numbers) or into memory to
 * free (heap). */
typedef struct {
    double *data;
    double *heap;
    PyObject *owned;
    int size;
} doubles;

static void release_doubles(doubles *d)
{
    PyMem_Free(d->heap);
    Py_XDECREF(d->owned);
    d->heap = NULL;
    d->owned = NULL;
}

/* `obj` as read-only doubles: a one-dimensional float64 array (its data; a contiguous copy
 * in the machine's byte order of a strided, misaligned or byte-swapped one), or a list or
 * tuple of floats and ints; 0 with the error set (naming `name`) otherwise. */
static int read_doubles(PyObject *obj, double *stack, const char *name, doubles *d)
{
    Py_ssize_t i, m;
    d->heap = NULL;
    d->owned = NULL;
    if (!PyList_Check(obj) && !PyTuple_Check(obj)) {
        if (PyArray_Check(obj) && PyArray_TYPE((PyArrayObject *)obj) == NPY_DOUBLE &&
            PyArray_NDIM((PyArrayObject *)obj) == 1 &&
            !(PyArray_IS_C_CONTIGUOUS((PyArrayObject *)obj) &&
              PyArray_ISALIGNED((PyArrayObject *)obj) &&
              PyArray_ISNOTSWAPPED((PyArrayObject *)obj))) {
            d->owned = PyArray_FROMANY(obj, NPY_DOUBLE, 1, 1, NPY_ARRAY_IN_ARRAY);
            if (d->owned == NULL)
                return 0;
            obj = d->owned;
        }
        d->data = array_data(obj, NPY_DOUBLE, 0, name, &d->size);
        if (d->data == NULL)
            release_doubles(d);
        return d->data != NULL;
    }
    m = PySequence_Fast_GET_SIZE(obj);
    if (m > INT_MAX) {
        PyErr_Format(PyExc_ValueError, "%s has more than %d entries", name, INT_MAX);
        return 0;
    }
    d->data = stack;
    if (m > STACK_DOUBLES) {
        d->heap = PyMem_Malloc((size_t)m*sizeof(double));
        if (d->heap == NULL) {
            PyErr_NoMemory();
            return 0;
        }
        d->data = d->heap;
    }
    /* floats (and their subclasses, numpy's float64) and ints only: reading them runs no
     * Python code, so the list cannot change while it is read */
    for (i = 0; i < m; i++) {
        PyObject *v = PySequence_Fast_GET_ITEM(obj, i);
        if (PyFloat_Check(v)) {
            d->data[i] = PyFloat_AS_DOUBLE(v);
        } else if (PyLong_CheckExact(v)) {
            d->data[i] = PyLong_AsDouble(v);
            if (d->data[i] == -1.0 && PyErr_Occurred()) {
                release_doubles(d);
                return 0;
            }
        } else {
            PyErr_Format(PyExc_TypeError, "%s[%zd] must be a float or an int, got %.100s",
                         name, i, Py_TYPE(v)->tp_name);
            release_doubles(d);
            return 0;
        }
    }
    d->size = (int)m;
    return 1;
}

/* A real number (float, int, numpy scalar: as float() converts it); 0 with the error set
 * otherwise. */
static int read_double(PyObject *obj, const char *name, double *x)
{
    *x = PyFloat_AsDouble(obj);
    if (*x == -1.0 && PyErr_Occurred()) {
        PyErr_Format(PyExc_TypeError, "%s must be a real number, got %.100s", name,
                     Py_TYPE(obj)->tp_name);
        return 0;
    }
    return 1;
}

/* A Python int in the range of `lo`..`hi`; 0 with the error set otherwise. */
static int read_integer(PyObject *obj, const char *name, long long lo, long long hi,
                        long long *k)
{
    if (!PyLong_Check(obj)) {
        PyErr_Format(PyExc_TypeError, "%s must be an int, got %.100s", name,
                     Py_TYPE(obj)->tp_name);
        return 0;
    }
    *k = PyLong_AsLongLong(obj);
    if (*k == -1 && PyErr_Occurred())
        return 0;
    if (*k < lo || *k > hi) {
        PyErr_Format(PyExc_ValueError, "%s = %lld is out of range", name, *k);
        return 0;
    }
    return 1;
}

/* The iout argument: an int64 array of IOUT_SIZE numbers, writeable. */
static int64_t *iout_data(PyObject *obj)
{
    int size;
    int64_t *iout = array_data(obj, NPY_INT64, 1, "iout", &size);
    if (iout != NULL && size != IOUT_SIZE) {
        PyErr_Format(PyExc_ValueError, "iout must have %d entries, got %d", IOUT_SIZE,
                     size);
        return NULL;
    }
    return iout;
}

/* The leading arguments of every entry: their number (`expected`, positional), the
 * handle of the kept propagation and its parameters (read into `stack` or beyond, as
 * read_doubles); 0 with the error set otherwise (nothing to release). */
static int read_head(const char *fname, PyObject *const *args, Py_ssize_t nargs,
                     Py_ssize_t expected, int64_t *handle, double *stack, doubles *params)
{
    long long k;
    if (nargs != expected) {
        PyErr_Format(PyExc_TypeError, "%s() takes %zd positional arguments (%zd given)",
                     fname, expected, nargs);
        return 0;
    }
    if (!read_integer(args[0], "handle", LLONG_MIN, LLONG_MAX, &k))
        return 0;
    *handle = (int64_t)k;
    return read_doubles(args[1], stack, "params", params);
}

PyDoc_STRVAR(until_doc,
"until(handle, params, t0, t1, y, iout)\n--\n\n"
"flat_propagation_until(handle, params, t0, t1, y, iout) (y and iout written in place):\n"
"one propagation of y from t0 to t1 by the kept propagation at handle.");

static PyObject *until(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    double stack_p[STACK_DOUBLES];
    doubles params;
    int64_t handle, *iout;
    int n;
    double t0, t1, *y;
    PyObject *res = NULL;
    (void)self;
    if (!read_head("until", args, nargs, 6, &handle, stack_p, &params))
        return NULL;
    if (!read_double(args[2], "t0", &t0) || !read_double(args[3], "t1", &t1))
        goto done;
    y = array_data(args[4], NPY_DOUBLE, 1, "y", &n);
    if (y == NULL || (iout = iout_data(args[5])) == NULL)
        goto done;
    flat_propagation_until_(&handle, &params.size, params.data, &t0, &t1, &n, y, iout);
    res = Py_None;
    Py_INCREF(res);
done:
    release_doubles(&params);
    return res;
}

PyDoc_STRVAR(solve_doc,
"solve(handle, params, t0, tf, y0, h0, hmax, max_steps, with_t_eval, neval, t_eval, out,\n"
"      iout)\n--\n\n"
"flat_propagation_solve with these arguments (out and iout written in place): a\n"
"solve_ivp run by the kept propagation at handle. y0 and t_eval: float64 arrays, or\n"
"lists or tuples of floats and ints.");

static PyObject *solve(PyObject *self, PyObject *const *args, Py_ssize_t nargs)
{
    double stack_p[STACK_DOUBLES], stack_y[STACK_DOUBLES], stack_t[STACK_DOUBLES];
    doubles params, y0 = {NULL, NULL, NULL, 0}, te = {NULL, NULL, NULL, 0};
    long long ms, wt, ne;
    int64_t handle, *iout;
    int nout, max_steps, with_t_eval, neval;
    double t0, tf, h0, hmax, *out;
    PyObject *res = NULL;
    (void)self;
    if (!read_head("solve", args, nargs, 13, &handle, stack_p, &params))
        return NULL;
    if (!read_double(args[2], "t0", &t0) || !read_double(args[3], "tf", &tf) ||
        !read_doubles(args[4], stack_y, "y0", &y0))
        goto done;
    if (!read_double(args[5], "h0", &h0) || !read_double(args[6], "hmax", &hmax) ||
        !read_integer(args[7], "max_steps", INT_MIN, INT_MAX, &ms) ||
        !read_integer(args[8], "with_t_eval", INT_MIN, INT_MAX, &wt) ||
        !read_integer(args[9], "neval", INT_MIN, INT_MAX, &ne) ||
        !read_doubles(args[10], stack_t, "t_eval", &te))
        goto done;
    max_steps = (int)ms;
    with_t_eval = (int)wt;
    neval = (int)ne;
    out = array_data(args[11], NPY_DOUBLE, 1, "out", &nout);
    if (out == NULL || (iout = iout_data(args[12])) == NULL)
        goto done;
    flat_propagation_solve_(&handle, &params.size, params.data, &t0, &tf, &y0.size, y0.data,
                            &h0, &hmax, &max_steps, &with_t_eval, &neval, &te.size, te.data,
                            &nout, out, iout);
    res = Py_None;
    Py_INCREF(res);
done:
    release_doubles(&params);
    release_doubles(&y0);
    release_doubles(&te);
    return res;
}

static PyMethodDef methods[] = {
    {"until", (PyCFunction)(void (*)(void))until, METH_FASTCALL, until_doc},
    {"solve", (PyCFunction)(void (*)(void))solve, METH_FASTCALL, solve_doc},
    {NULL, NULL, 0, NULL}
};

static struct PyModuleDef fastcall_module = {
    PyModuleDef_HEAD_INIT, "_fastcall",
    "The flat layer's per-call entries for conmech.Propagator and solve_ivp's fast entry "
    "(python/conmech/flat/fastcall.c).", -1, methods, NULL, NULL, NULL, NULL
};

PyMODINIT_FUNC PyInit__fastcall(void)
{
    import_array();
    return PyModule_Create(&fastcall_module);
}
