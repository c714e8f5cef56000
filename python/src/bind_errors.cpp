// mbsflow.Error and its subclasses: every library error, with the CLI's message, a setting
// written as the Python keyword that sets it ("macro_step=0.5", not "--macro-step 0.5").
#include "bindings.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/runtime/run_settings.hpp"

namespace mbsflow::python {
namespace {

// Made once and kept for the life of the process (a static py::object would be released
// after the interpreter is gone).
PyObject* error_type = nullptr;
PyObject* input_error_type = nullptr;
PyObject* run_error_type = nullptr;
PyObject* model_error_type = nullptr;

PyObject* new_type(const char* name, const char* doc, PyObject* bases) {
  PyObject* t = PyErr_NewExceptionWithDoc(name, doc, bases, nullptr);
  if (!t) throw py::error_already_set();
  return t;
}

}  // namespace

std::string keyword_for(const std::string& setting, const std::string* value) {
  const RunSetting* s = find_run_setting(setting);
  const std::string name = s ? s->keyword() : setting;
  if (!value) return name;
  if (value->find(',') == std::string::npos) return name + "=" + *value;
  std::string list;  // "A1,A2,..." is a list in Python: [A1, A2, ...]
  for (char c : *value) list += c == ',' ? std::string(", ") : std::string(1, c);
  return name + "=[" + list + "]";
}

void bind_errors(py::module_& m) {
  error_type = new_type("mbsflow.Error", "Every error of mbsflow.", PyExc_Exception);
  input_error_type = new_type("mbsflow.InputError", "Bad input: a model, a setting or an argument (the CLI's exit code 2).",
                              py::make_tuple(py::handle(error_type), py::handle(PyExc_ValueError)).ptr());
  run_error_type = new_type("mbsflow.RunError", "A run that could not be completed: diverged, step too small, interrupted.",
                            py::make_tuple(py::handle(error_type), py::handle(PyExc_RuntimeError)).ptr());
  model_error_type = new_type("mbsflow.ModelError", "Bad input in a model that shows once it is set up (a rigid joint its "
                              "bodies do not meet); a run of a model file names the file.",
                              py::make_tuple(py::handle(input_error_type)).ptr());
  m.attr("Error") = py::handle(error_type);
  m.attr("ModelError") = py::handle(model_error_type);
  m.attr("InputError") = py::handle(input_error_type);
  m.attr("RunError") = py::handle(run_error_type);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ModelError& e) {
      PyErr_SetString(model_error_type, render(e.text(), keyword_for).c_str());
    } catch (const InputError& e) {
      PyErr_SetString(input_error_type, render(e.text(), keyword_for).c_str());
    } catch (const RunError& e) {
      PyErr_SetString(run_error_type, render(e.text(), keyword_for).c_str());
    } catch (const Error& e) {
      PyErr_SetString(error_type, render(e.text(), keyword_for).c_str());
    }
  });
}

}  // namespace mbsflow::python
