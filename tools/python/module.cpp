// The seamvox Python module: numpy arrays in and out of the library pipeline (parameterize),
// the mesh readers and writers, the check verdict, the cross field and the quad mesh. Errors map
// to the exception classes made in makeExceptions, with the library's messages.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <string>

#include "core/pipeline/parameterize.h"
#include "core/quads/checked.h"
#include "core/quality/check.h"
#include "core/system/blas_threads.h"
#include "core/system/errors.h"
#include "io/check_report.h"
#include "io/mesh_io.h"
#include "io/param_report.h"
#include "io/quad_report.h"
#include "tools/python/arrays.h"
#include "tools/python/interruptible.h"

namespace seamvox::python {
namespace {

/// What a caller's arrays are called in reports (the command puts the file name there).
constexpr const char* kArraysName = "<arrays>";

/// The outcome of parameterize(): the cleaned mesh the map is on, the map and its figures.
struct ParamOutcome {
  py::object V, F, uv, cones, quality, report;
  std::uint32_t seams = 0;
};

/// The outcome of cross_field().
struct FieldOutcome {
  py::object V, F, field, cones;
  std::uint32_t seams = 0;
  std::string method;
};

/// The outcome of quads(): the quad mesh, its validation and report.
struct QuadsOutcome {
  py::object V, faces, polygons, report;
  bool valid = false;
  double quadFraction = 0.0;
};

py::object parseJson(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

/// A path given as str or os.PathLike.
std::string pathArg(const py::object& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

/// An argument that must be a whole number (int or numpy integer, not bool) from min to max.
long wholeNumberArg(const py::object& x, const char* name, long min, long max) {
  long n = min - 1;
  if (PyIndex_Check(x.ptr()) && !py::isinstance<py::bool_>(x)) {  // int, numpy integers
    n = PyLong_AsLong(py::int_(x).ptr());
    if (n == -1 && PyErr_Occurred()) {
      PyErr_Clear();
      n = min - 1;
    }
  }
  if (n < min || n > max) {
    throw InputError(std::string(name) + " must be a whole number from " + std::to_string(min) + " to " +
                     std::to_string(max) + ", got " + std::string(py::repr(x)));
  }
  return n;
}

int threadCount(const py::object& threads) {
  if (threads.is_none()) return 0;
  return static_cast<int>(wholeNumberArg(threads, "threads", 1, 4096));
}

/// edge_length= of parameterize, cross_field and check: None (0) or a positive finite number.
double edgeLengthArg(const py::object& edgeLength) {
  if (edgeLength.is_none()) return 0.0;
  double h = 0.0;
  if (!py::isinstance<py::str>(edgeLength) && !py::isinstance<py::bytes>(edgeLength)) {
    h = PyFloat_AsDouble(edgeLength.ptr());  // float, int, numpy scalars
    if (h == -1.0 && PyErr_Occurred()) PyErr_Clear();
  }
  if (!(h > 0.0 && std::isfinite(h))) {
    throw InputError("edge_length must be a positive finite number, got " + std::string(py::repr(edgeLength)));
  }
  return h;
}

GridSpacing gridSpacing(double cells, const py::object& edgeLength) {
  GridSpacing spacing;
  if (!edgeLength.is_none()) {
    spacing.edgeLength = edgeLengthArg(edgeLength);
  } else {
    if (!(cells > 0.0)) throw InputError("cells must be a positive number, got " + std::to_string(cells));
    spacing.cells = cells;
  }
  spacing.validate();
  return spacing;
}

/// field_smoothing= of parameterize and cross_field (`--field-smoothing`): 1..64 steps, and only for a
/// computed field (an array has no smoothed surface).
std::uint32_t fieldSmoothingSteps(std::int64_t steps, const FieldSource& source) {
  if (steps < 1 || steps > 64) {
    throw InputError("field_smoothing must be an integer from 1 to 64, got " + std::to_string(steps));
  }
  if (!source.importedPerInputFace.empty() && steps != kFieldSmoothingIterations) {
    throw InputError("field_smoothing has no effect with a field array (it smooths the surface a computed field is solved on)");
  }
  return static_cast<std::uint32_t>(steps);
}

double mergeFraction(double mergeCones) {
  if (!(mergeCones >= 0.0 && mergeCones <= 10.0)) {
    throw InputError("merge_cones must be a number from 0 to 10 (grid spacings), got " + std::to_string(mergeCones));
  }
  return mergeCones;
}

/// field= of parameterize and cross_field: a method name, or one vector per face of F.
/// Returns the name the report gives it.
std::string fieldSource(const py::object& field, std::size_t faces, FieldSource& source) {
  if (field.is_none()) return "auto";
  if (py::isinstance<py::str>(field)) {
    const std::string name = field.cast<std::string>();
    source.method = parseFieldMethod(name);
    return name;
  }
  source.importedPerInputFace = vectorsFromArray(field, faces, "field");
  return "array";
}

ParamOutcome parameterizeArrays(const py::object& V, const py::object& F, const std::string& solver, double cells,
                                const py::object& edgeLength, std::int32_t grid, const py::object& field,
                                double mergeCones, const py::object& threads, const py::object& progress,
                                bool untangle, bool weld, double closeHoles, std::int64_t fieldSmoothing,
                                bool roughSpots) {
  TriangleMesh raw = meshFromArrays(V, F);
  if (!(closeHoles >= 0.0 && closeHoles <= 1000.0)) {
    throw InputError("close_holes must be a number from 0 to 1000 (grid spacings), got " + std::to_string(closeHoles));
  }
  PipelineOptions options;
  options.solver.solver = parseParamSolver(solver);
  if (grid < 4 || grid > 1024 || (grid & (grid - 1)) != 0) {
    throw InputError("grid must be a power of two from 4 to 1024, got " + std::to_string(grid));
  }
  options.solver.gridResolution = grid;
  options.spacing = gridSpacing(cells, edgeLength);
  options.mergeCones = mergeFraction(mergeCones);
  options.untangle = untangle;
  options.clean.weldVertices = weld;
  options.closeHoles = closeHoles;
  const std::string fieldName = fieldSource(field, raw.numFaces(), options.field);
  options.field.smoothingSteps = fieldSmoothingSteps(fieldSmoothing, options.field);
  options.field.roughSpots = roughSpots;
  Interruptible interruptible(progress, threadCount(threads));
  options.progress = interruptible.progressFn();
  StageMeter meter;
  options.meter = &meter;
  PipelineResult r;
  interruptible.run([&] { r = parameterize(std::move(raw), options); });

  ParamOutcome out;
  out.V = positionsArray(r.mesh);
  out.F = facesArray(r.mesh);
  out.uv = cornerUVArray(r.mesh);
  out.cones = conesArray(r.cones, r.coneIndex4);
  out.seams = r.seams;
  // The command's report, from the same writer.
  out.report = parseJson(paramReportJson(r, paramReportContext(options, meter, kArraysName, "", solver, fieldName)));
  out.quality = out.report["quality"];
  return out;
}

FieldOutcome crossFieldArrays(const py::object& V, const py::object& F, const std::string& method, double curvature,
                              double mergeCones, double cells, const py::object& edgeLength,
                              const py::object& threads, const py::object& progress, std::int64_t fieldSmoothing,
                              bool roughSpots) {
  TriangleMesh raw = meshFromArrays(V, F);
  const std::uint32_t inputFaces = raw.numFaces();
  FieldSource source;
  fieldSource(py::str(method), inputFaces, source);
  source.smoothingSteps = fieldSmoothingSteps(fieldSmoothing, source);
  source.roughSpots = roughSpots;
  if (!(curvature >= 0.0 && std::isfinite(curvature))) {
    throw InputError("curvature must be a finite number >= 0, got " + std::to_string(curvature));
  }
  source.curvatureWeight = curvature;
  const GridSpacing spacing = gridSpacing(cells, edgeLength);
  const double merge = mergeFraction(mergeCones);
  Interruptible interruptible(progress, threadCount(threads));
  const ProgressFn progressFn = interruptible.progressFn();
  // As `seamvox field` computes it: clean, field, the cones param cuts through (merged as param
  // merges them before its first cut, with h from the diagonal without spikes).
  CleanResult clean;
  CrossField crossField;
  ConeCut coneCut;
  interruptible.run([&] {
    CleanOptions cleanOptions;
    cleanOptions.progress = progressFn;
    clean = cleanMesh(std::move(raw), cleanOptions);
    const double h = spacing.spacing(clean.report.diagonalWithoutSpikes);
    source.gridLength = h;  // as parameterize sets it
    crossField = computeFieldFromSource(clean.mesh, clean.topology, clean.faceOrigin, inputFaces, source, progressFn);
    coneCut = cutThroughCones(clean.mesh, clean.topology, crossField, merge * h, {}, 0.0, progressFn);
  });
  FieldOutcome out;
  // One vector per input face, as `seamvox field` writes it: faces cleaning dropped get zero.
  std::vector<Vec3d> perInputFace(inputFaces, Vec3d::Zero());
  for (FaceId f = 0; f < clean.mesh.numFaces(); ++f) perInputFace[clean.faceOrigin[f]] = crossField.at(f);
  out.field = vectorsArray(perInputFace);
  out.V = positionsArray(clean.mesh);
  out.F = facesArray(clean.mesh);
  const FieldSingularities& sing = coneCut.singularities;
  std::vector<std::int32_t> index4;
  for (VertexId v : sing.cones) index4.push_back(sing.index4[v]);
  out.cones = conesArray(sing.cones, index4);
  out.seams = static_cast<std::uint32_t>(coneCut.cut.seams.size());
  out.method = fieldMethodName(resolveFieldMethod(source.method, clean.mesh.numFaces()));
  return out;
}

py::dict checkArrays(const py::object& V, const py::object& F, const py::object& uv, const py::object& field,
                     const py::object& edgeLength, double tolerance) {
  TriangleMesh raw = meshFromArrays(V, F, uv);
  CheckOptions options;
  options.edgeLength = edgeLengthArg(edgeLength);
  if (!(tolerance >= 0.0 && std::isfinite(tolerance))) {
    throw InputError("tolerance must be a finite number >= 0, got " + std::to_string(tolerance));
  }
  options.tolerance = tolerance;
  if (!field.is_none()) options.fieldPerInputFace = vectorsFromArray(field, raw.numFaces(), "field");
  CheckResult r;
  {
    py::gil_scoped_release release;
    r = checkParameterization(std::move(raw), options);
  }
  return parseJson(checkReportJson(kArraysName, r));
}

QuadsOutcome quadsArrays(const py::object& V, const py::object& F, const py::object& uv, const py::object& scale,
                         bool weld, const py::object& threads, const py::object& progress) {
  TriangleMesh raw = meshFromArrays(V, F, uv);
  const std::int64_t k = wholeNumberArg(scale, "scale", 1, 1 << 20);  // as `seamvox quads --scale`
  Interruptible interruptible(progress, threadCount(threads));
  const ProgressFn progressFn = interruptible.progressFn();
  StageMeter meter;
  QuadRun run;
  std::uint32_t mapFaces = 0;
  interruptible.run([&] {
    CleanOptions cleanOptions;
    cleanOptions.weldVertices = weld;
    cleanOptions.progress = progressFn;
    const CleanResult cleaned = cleanMesh(std::move(raw), cleanOptions);
    mapFaces = cleaned.mesh.numFaces();
    meter.finish("clean");
    run = extractCheckedQuads(kArraysName, cleaned.mesh, cleaned.topology, k, progressFn);
    meter.finish("quads");
  });
  QuadsOutcome out;
  out.V = vectorsArray(run.quads.mesh.positions);
  auto [quads, polygons] = polygonFacesArrays(run.quads.mesh);
  out.faces = std::move(quads);
  out.polygons = std::move(polygons);
  out.valid = run.check.isValid();
  out.quadFraction = run.check.quadFraction;
  // The command's report, from the same writer.
  out.report = parseJson(
      quadReportJson(run.quads, run.check, quadReportContext(run, mapFaces, k, meter, kArraysName, "")));
  return out;
}

py::tuple readMeshArrays(const py::object& pathLike, bool uv) {
  const std::string path = pathArg(pathLike);
  ReadOptions options;
  options.readUV = uv;
  TriangleMesh mesh;
  {
    py::gil_scoped_release release;
    mesh = readMesh(path, options);
  }
  if (!uv) return py::make_tuple(positionsArray(mesh), facesArray(mesh));
  return py::make_tuple(positionsArray(mesh), facesArray(mesh),
                        mesh.hasUV() ? py::object(cornerUVArray(mesh)) : py::object(py::none()));
}

void writeMeshArrays(const py::object& pathLike, const py::object& V, const py::object& F, const py::object& uv) {
  const std::string path = pathArg(pathLike);
  const TriangleMesh mesh = meshFromArrays(V, F, uv);
  py::gil_scoped_release release;
  writeMesh(path, mesh);
}

/// The exception types of makeExceptions, kept for the module's life (never released: the
/// translator may run until the interpreter exits).
struct ExceptionTypes {
  PyObject *error, *input, *io, *topology, *solver, *cancelled;
};
ExceptionTypes exceptionTypes;

/// seamvox.Error and its subclasses, each also a subclass of the Python exception that fits.
void makeExceptions(py::module_& m) {
  auto make = [&](const char* name, py::handle bases, const char* doc) {
    const std::string qualified = std::string("seamvox.") + name;
    PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
    if (!type) throw py::error_already_set();
    m.attr(name) = py::handle(type);
    return type;
  };
  ExceptionTypes& t = exceptionTypes;
  t.error = make("Error", PyExc_Exception, "Base of every seamvox error.");
  const auto both = [&](PyObject* builtin) { return py::make_tuple(py::handle(t.error), py::handle(builtin)); };
  t.input = make("InputError", both(PyExc_ValueError),
                 "Invalid input: a bad array (shape, dtype, index, NaN), option or file content. A ValueError.");
  t.io = make("IoError", both(PyExc_OSError), "A file could not be opened, read or written. An OSError.");
  t.topology = make("TopologyError", both(PyExc_RuntimeError),
                    "The mesh lacks the topology a stage needs. A RuntimeError.");
  t.solver = make("SolverError", both(PyExc_RuntimeError), "A numerical stage failed. A RuntimeError.");
  t.cancelled = make("CancelledError", both(PyExc_RuntimeError),
                     "The work was cancelled by progress returning False. A RuntimeError.");
  py::register_exception_translator([](std::exception_ptr p) {
    const ExceptionTypes& t = exceptionTypes;
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(t.input, e.what());
    } catch (const IoError& e) {
      PyErr_SetString(t.io, e.what());
    } catch (const TopologyError& e) {
      PyErr_SetString(t.topology, e.what());
    } catch (const SolverError& e) {
      PyErr_SetString(t.solver, e.what());
    } catch (const CancelledError& e) {
      PyErr_SetString(t.cancelled, e.what());
    } catch (const Error& e) {
      PyErr_SetString(t.error, e.what());
    }
  });
}

template <class T>
void addArrayFields(py::class_<T>& c) {
  c.def_readonly("V", &T::V, "(n, 3) float64 vertex positions of the cleaned mesh")
      .def_readonly("F", &T::F, "(m, 3) int64 faces of the cleaned mesh")
      .def_readonly("cones", &T::cones, "(k, 2) int64 rows (vertex id in V, index in quarter turns)")
      .def_readonly("seams", &T::seams, "number of seam curves of the cut");
}

}  // namespace
}  // namespace seamvox::python

PYBIND11_MODULE(seamvox, m) {
  using namespace seamvox::python;
  namespace sv = seamvox;
  m.doc() =
      "Global seamless parameterization of triangle meshes (numpy arrays in and out).\n\n"
      "Meshes are V (n, 3) float32/float64 and F (m, 3) integer arrays. Every stage cleans the\n"
      "mesh first (degenerate and duplicate faces dropped, non-manifold elements split); results\n"
      "hold the cleaned mesh (V, F) the map is on, which is the input itself for a clean mesh.\n"
      "Errors: seamvox.InputError (a ValueError), IoError (an OSError), TopologyError and\n"
      "SolverError (RuntimeErrors), CancelledError; all derive from seamvox.Error.";
  m.attr("__version__") = SEAMVOX_VERSION;
  makeExceptions(m);
  // Each docstring starts with its own signature (pybind11's would say "V: object").
  py::options options;
  options.disable_function_signatures();
  // seamvox's loops run on TBB; a second pool of BLAS threads slows CHOLMOD down (as the command).
  sv::limitBlasThreads(1);
  // OpenBLAS chose its kernels as it loaded; the command re-runs itself with better ones, a
  // module can only say so.
  const std::string blasCore = sv::preferredBlasCore();
  if (!blasCore.empty()) {
    const std::string message = "seamvox: OpenBLAS runs its generic '" + sv::blasCoreName() +
                                "' kernels on this processor; OPENBLAS_CORETYPE=" + blasCore +
                                " set before Python starts makes the solves faster";
    PyErr_WarnEx(PyExc_RuntimeWarning, message.c_str(), 1);
  }

  py::class_<ParamOutcome> result(m, "Result", "A seamless parameterization (seamvox.parameterize).");
  addArrayFields(result);
  result.def_readonly("uv", &ParamOutcome::uv, "(m, 3, 2) float64 per-corner (u, v) in grid units, rows of F")
      .def_readonly("quality", &ParamOutcome::quality,
                    "dict: seamless, maxSeamResidual, maxIntegerDistance, relativeGradientError, flipped, ...")
      .def_readonly("report", &ParamOutcome::report, "dict: the report of `seamvox param --report`")
      .def("__repr__", [](const ParamOutcome& r) {
        return "<seamvox.Result: " + std::to_string(py::len(r.F)) + " faces, " + std::to_string(py::len(r.cones)) +
               " cones, " + std::to_string(r.seams) + " seams, " +
               (r.quality["seamless"].cast<bool>() ? "seamless>" : "NOT seamless>");
      });

  py::class_<FieldOutcome> field(m, "FieldResult", "A cross field with its cones and cut (seamvox.cross_field).");
  addArrayFields(field);
  field.def_readonly("field", &FieldOutcome::field,
                     "(m, 3) float64 unit direction per face of the input F (zero for faces cleaning dropped); "
                     "parameterize(V, F, field=...) takes it")
      .def_readonly("method", &FieldOutcome::method, "\"direct\" or \"proxy\"");

  py::class_<QuadsOutcome> quadResult(m, "QuadResult", "The quad mesh of a seamless map (seamvox.quads).");
  quadResult.def_readonly("V", &QuadsOutcome::V, "(k, 3) float64 vertex positions")
      .def_readonly("faces", &QuadsOutcome::faces, "(q, 4) int64 quad faces (rows into V, counter-clockwise)")
      .def_readonly("polygons", &QuadsOutcome::polygons,
                    "list of 1-D int64 arrays: the faces that are not quads (at cones and the boundary)")
      .def_readonly("valid", &QuadsOutcome::valid, "every check of the validation holds (report['validation'])")
      .def_readonly("quad_fraction", &QuadsOutcome::quadFraction, "quads / faces")
      .def_readonly("report", &QuadsOutcome::report, "dict: the report of `seamvox quads --report`")
      .def("__repr__", [](const QuadsOutcome& q) {
        return "<seamvox.QuadResult: " + std::to_string(py::len(q.faces)) + " quads, " +
               std::to_string(py::len(q.polygons)) + " other faces, " + (q.valid ? "valid>" : "NOT valid>");
      });

  m.def("read_mesh", &readMeshArrays, py::arg("path"), py::kw_only(), py::arg("uv") = false,
        "read_mesh(path, *, uv=False) -> (V, F) or, with uv=True, (V, F, uv or None)\n\n"
        "PLY, OBJ, OFF or Draco (.drc). V is (n, 3) float64, F (m, 3) int64, uv (m, 3, 2) float64.");
  m.def("write_mesh", &writeMeshArrays, py::arg("path"), py::arg("V"), py::arg("F"), py::arg("uv") = py::none(),
        "write_mesh(path, V, F, uv=None)\n\n"
        "Writes PLY, OBJ, OFF or Draco (by extension), uv (m, 3, 2) per corner when given; the file\n"
        "is written whole or not at all.");
  m.def("parameterize", &parameterizeArrays, py::arg("V"), py::arg("F"), py::kw_only(),
        py::arg("solver") = "auto", py::arg("cells") = 100.0, py::arg("edge_length") = py::none(),
        py::arg("grid") = 128, py::arg("field") = py::none(), py::arg("merge_cones") = seamvox::kConeMergeFraction,
        py::arg("threads") = py::none(), py::arg("progress") = py::none(), py::arg("untangle") = true,
        py::arg("weld") = false, py::arg("close_holes") = 0.0, py::arg("field_smoothing") = seamvox::kFieldSmoothingIterations,
        py::arg("rough_spots") = true,
        "parameterize(V, F, *, solver='auto', cells=100, edge_length=None, grid=128, field=None,\n"
        "             merge_cones=1, threads=None, progress=None, untangle=True, weld=False,\n"
        "             close_holes=0, field_smoothing=3, rough_spots=True) -> Result\n\n"
        "The pipeline of `seamvox param` with the same defaults (so the same map). solver: 'auto',\n"
        "'hat', 'vox' or 'voxloc'; grid spacing h = edge_length, or the bounding-box diagonal / cells;\n"
        "field: None or 'auto', 'smooth', 'proxy', or an (m, 3) array of one direction per face of F;\n"
        "threads: worker threads (None: all cores). progress(stage, fraction) is called from the\n"
        "work as it goes; returning False cancels (seamvox.CancelledError), an exception it raises\n"
        "cancels and is re-raised, and Ctrl-C cancels with KeyboardInterrupt. The GIL is released.\n"
        "close_holes: holes within that many grid spacings carry no seam translation, so quads() can\n"
        "close them (`seamvox param --close-holes`; 2 is what `param --quads` uses).\n"
        "field_smoothing: smoothing steps (1..64) of the surface a computed field and its cones are\n"
        "read on (`seamvox param --field-smoothing`); rough_spots=False: its crumpled spots are not\n"
        "smoothed further within h (`seamvox param --no-rough-spots`).");
  m.def("cross_field", &crossFieldArrays, py::arg("V"), py::arg("F"), py::kw_only(), py::arg("field") = "auto",
        py::arg("curvature") = 0.0, py::arg("merge_cones") = seamvox::kConeMergeFraction, py::arg("cells") = 100.0,
        py::arg("edge_length") = py::none(), py::arg("threads") = py::none(), py::arg("progress") = py::none(),
        py::arg("field_smoothing") = seamvox::kFieldSmoothingIterations, py::arg("rough_spots") = true,
        "cross_field(V, F, *, field='auto', curvature=0.0, merge_cones=1, cells=100,\n"
        "            edge_length=None, threads=None, progress=None, field_smoothing=3,\n"
        "            rough_spots=True) -> FieldResult\n\n"
        "The cross field, its cones (merged as parameterize merges them before its first cut) and\n"
        "the cut, as `seamvox field` computes them. field: 'auto', 'smooth' or 'proxy'; curvature > 0\n"
        "aligns the direct field with principal curvature. progress and Ctrl-C as in parameterize.");
  m.def("check", &checkArrays, py::arg("V"), py::arg("F"), py::arg("uv"), py::kw_only(),
        py::arg("field") = py::none(), py::arg("edge_length") = py::none(), py::arg("tolerance") = 1e-6,
        "check(V, F, uv, *, field=None, edge_length=None, tolerance=1e-6) -> dict\n\n"
        "The verdict of `seamvox check --json` on per-corner uv (m, 3, 2): seams found from the uv\n"
        "alone, residual, integer distance, flips, collapses and, with a field (m, 3), the relative\n"
        "gradient error; 'seamless' is True when both seam figures are <= tolerance.");
  m.def("quads", &quadsArrays, py::arg("V"), py::arg("F"), py::arg("uv"), py::kw_only(), py::arg("scale") = 1,
        py::arg("weld") = false, py::arg("threads") = py::none(), py::arg("progress") = py::none(),
        "quads(V, F, uv, *, scale=1, weld=False, threads=None, progress=None) -> QuadResult\n\n"
        "The quad mesh of `seamvox quads` from per-corner uv (m, 3, 2) in grid units, which must be\n"
        "seamless (as parameterize makes it): a vertex at every integer point, edges along the integer\n"
        "iso-lines (every `scale` units), validated against the map's topology. Q.faces holds the quads\n"
        "as a (q, 4) array and Q.polygons the other faces (where iso-lines meet cones or the boundary),\n"
        "each in the order of the command's file. A map that is not seamless, uv=None or a scale that\n"
        "does not divide the seam translations raises seamvox.InputError with the command's message.\n"
        "progress and Ctrl-C as in parameterize.");
}
