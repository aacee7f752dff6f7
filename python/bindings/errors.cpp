// sinew's typed exceptions as Python exceptions. Each carries the tools' own message (str(e)) and
// its parts as attributes: e.file, e.field, e.problem, e.index (None when the error has none).
//
//   sinew.Error (RuntimeError)
//     InputError (+ ValueError): ConfigError, FormatError, GeometryError — bad input
//     IoError (+ OSError): a file that cannot be opened, read or written
//     UnstableError: the simulation became unstable (NaN, inverted element, blow-up)
//     ResourceError: more than the machine has (memory, no GPU)
//
// The classes are made with PyErr_NewException, which takes a tuple of bases, so a caller may
// catch ValueError or OSError as for any Python library.
#include <pybind11/pybind11.h>

#include <exception>

#include "bindings.hpp"
#include "sinew/common/error.hpp"

namespace sinew::python {
namespace {

struct Classes {
  PyObject* error = nullptr;
  PyObject* input = nullptr;
  PyObject* config = nullptr;
  PyObject* format = nullptr;
  PyObject* geometry = nullptr;
  PyObject* io = nullptr;
  PyObject* unstable = nullptr;
  PyObject* resource = nullptr;
};
Classes g_classes;  // owned by the module (added to it), alive as long as it is

PyObject* make_class(py::module_& m, const char* name, py::tuple bases, const char* doc) {
  const std::string qualified = std::string("sinew.") + name;
  PyObject* cls = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (!cls) throw py::error_already_set();
  m.add_object(name, py::handle(cls));  // the module keeps a reference
  return cls;
}

void raise(PyObject* cls, const Error& e) {
  py::object instance =
      py::reinterpret_steal<py::object>(PyObject_CallOneArg(cls, py::str(e.what()).ptr()));
  if (!instance) return;  // the call set its own error
  instance.attr("file") = e.file().empty() ? py::object(py::none()) : py::str(e.file());
  instance.attr("field") = e.field().empty() ? py::object(py::none()) : py::str(e.field());
  instance.attr("problem") = py::str(e.problem());
  instance.attr("index") = e.index() ? py::object(py::int_(*e.index())) : py::object(py::none());
  PyErr_SetObject(cls, instance.ptr());
}

}  // namespace

void bind_errors(py::module_& m) {
  auto bases = [](std::initializer_list<PyObject*> list) {
    py::tuple t(list.size());
    std::size_t i = 0;
    for (PyObject* p : list) t[i++] = py::reinterpret_borrow<py::object>(py::handle(p));
    return t;
  };
  Classes& c = g_classes;
  c.error = make_class(m, "Error", bases({PyExc_RuntimeError}),
                       "Every error sinew raises: str(e) is the tools' message; e.file, e.field, "
                       "e.problem and e.index its parts (None where it has none).");
  c.input = make_class(m, "InputError", bases({c.error, PyExc_ValueError}),
                       "Bad input: a scene, spec, model, results file or argument that sinew "
                       "refuses.");
  c.config = make_class(m, "ConfigError", bases({c.input}),
                        "A scene, spec or argument with an unknown key, a wrong type or a value "
                        "out of range.");
  c.format = make_class(m, "FormatError", bases({c.input}),
                        "A file (model, results, checkpoint) whose contents break its format.");
  c.geometry = make_class(m, "GeometryError", bases({c.input}),
                          "Meshes that cannot make a model (empty, non-finite, inner outside "
                          "outer, ...).");
  c.io = make_class(m, "IoError", bases({c.error, PyExc_OSError}),
                    "A file that cannot be opened, read or written.");
  c.unstable = make_class(m, "UnstableError", bases({c.error}),
                          "The simulation became unstable (NaN/Inf, an inverted element, an "
                          "energy blow-up); the message names the step, element or node and "
                          "where.");
  c.resource = make_class(m, "ResourceError", bases({c.error}),
                          "More than the machine can give: memory, a GPU.");

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ConfigError& e) {
      raise(g_classes.config, e);
    } catch (const FormatError& e) {
      raise(g_classes.format, e);
    } catch (const GeometryError& e) {
      raise(g_classes.geometry, e);
    } catch (const IoError& e) {
      raise(g_classes.io, e);
    } catch (const InstabilityError& e) {
      raise(g_classes.unstable, e);
    } catch (const ResourceError& e) {
      raise(g_classes.resource, e);
    } catch (const Error& e) {
      raise(g_classes.error, e);
    }
  });
}

}  // namespace sinew::python
