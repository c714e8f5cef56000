#include "cvode_driver.hpp"

#include <cvode/cvode.h>
#include <cvode/cvode_proj.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_band.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <chrono>
#include <cmath>
#include <memory>

#include "mbsflow/methods/jacobian.hpp"
#include "mbsflow/methods/shifted_solver.hpp"

namespace mbsflow::cli {

const char* to_string(CvodeLinearSolver s) {
  switch (s) {
    case CvodeLinearSolver::dense: return "dense";
    case CvodeLinearSolver::band: return "band";
    default: return "klu";
  }
}

namespace {

struct Data {
  const OdeProblem* p;
  CvodeLinearSolver solver;
  Eigen::VectorXd y, f;
  std::unique_ptr<JacobianEvaluator> differences;  // when the problem has no Jacobian
  Eigen::SparseMatrix<double> jac;
  Eigen::SparseMatrix<double> zero_diagonal;  // stored zeros: CVODE adds I in place only where J has a diagonal
  long difference_evaluations = 0, jacobians = 0;
  std::function<void(double, Eigen::VectorXd&)> project;  // optional (run_cvode)
  Eigen::VectorXd projected;
};

int rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* data) {
  auto* d = static_cast<Data*>(data);
  d->y = Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y), d->p->size);
  d->p->evaluate(t, d->y, d->f);
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(ydot), d->p->size) = d->f;
  return d->f.allFinite() ? 0 : 1;  // 1: recoverable, CVODE retries with a smaller step
}

int jacobian(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix j, void* data, N_Vector, N_Vector, N_Vector) {
  auto* d = static_cast<Data*>(data);
  const Eigen::Index n = d->p->size;
  d->y = Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y), n);
  ++d->jacobians;
  if (d->differences) {
    d->f = Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(fy), n);
    d->jac = d->differences->evaluate(t, d->y, d->f, d->difference_evaluations);
  } else {
    d->p->jacobian(t, d->y, d->jac);
  }
  if (d->solver == CvodeLinearSolver::klu) {
    d->jac = d->jac + d->zero_diagonal;
    // Compressed sparse columns, the layout of both.
    const Eigen::Index nnz = d->jac.nonZeros();
    if (SM_NNZ_S(j) < nnz) SUNSparseMatrix_Reallocate(j, nnz);
    for (Eigen::Index c = 0; c <= n; ++c) SM_INDEXPTRS_S(j)[c] = d->jac.outerIndexPtr()[c];
    for (Eigen::Index k = 0; k < nnz; ++k) {
      SM_INDEXVALS_S(j)[k] = d->jac.innerIndexPtr()[k];
      SM_DATA_S(j)[k] = d->jac.valuePtr()[k];
    }
    return 0;
  }
  SUNMatZero(j);
  for (Eigen::Index c = 0; c < d->jac.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(d->jac, c); it; ++it) {
      if (d->solver == CvodeLinearSolver::band)
        SM_ELEMENT_B(j, it.row(), it.col()) = it.value();
      else
        SM_ELEMENT_D(j, it.row(), it.col()) = it.value();
    }
  return 0;
}

// CVODE's projection (cvode_proj.h): the state of every accepted step put back where
// `project` puts it; corr = projected - ycur, the error estimate left as it is.
int project(sunrealtype t, N_Vector ycur, N_Vector corr, sunrealtype, N_Vector, void* data) {
  auto* d = static_cast<Data*>(data);
  const Eigen::Map<const Eigen::VectorXd> y(N_VGetArrayPointer(ycur), d->p->size);
  d->projected = y;
  d->project(t, d->projected);
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(corr), d->p->size) = d->projected - y;
  return 0;
}

}  // namespace

CvodeOutcome run_cvode(const OdeProblem& p, double rtol, double atol, CvodeLinearSolver solver,
                       const std::vector<double>& outputs, const std::function<void(double, const double*)>& on_output,
                       const Eigen::VectorXd& atols, const std::function<void(double, Eigen::VectorXd&)>& projection) {
  CvodeOutcome o;
  SUNContext ctx;
  SUNContext_Create(nullptr, &ctx);
  N_Vector y = N_VNew_Serial(p.size, ctx);
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y), p.size) = p.y0;
  Data d{&p, solver, Eigen::VectorXd(p.size), Eigen::VectorXd(p.size), nullptr, {}, {}, 0, 0, projection, {}};
  d.zero_diagonal.resize(p.size, p.size);
  d.zero_diagonal.setIdentity();
  d.zero_diagonal *= 0.0;
  if (!p.jacobian) d.differences = std::make_unique<JacobianEvaluator>(p, true);
  Eigen::SparseMatrix<double> pattern = p.sparsity ? *p.sparsity : Eigen::MatrixXd::Ones(p.size, p.size).sparseView();
  pattern.makeCompressed();
  d.jac = pattern + d.zero_diagonal;  // the problem's Jacobian writes its values into this pattern
  SUNMatrix a = nullptr;
  SUNLinearSolver ls = nullptr;
  if (solver == CvodeLinearSolver::klu) {
    a = SUNSparseMatrix(p.size, p.size, pattern.nonZeros() + p.size, CSC_MAT, ctx);
    ls = SUNLinSol_KLU(y, a, ctx);
  } else if (solver == CvodeLinearSolver::band) {
    const Bandwidth bw = bandwidth_of(pattern);
    a = SUNBandMatrix(p.size, bw.upper, bw.lower, ctx);
    ls = SUNLinSol_Band(y, a, ctx);
  } else {
    a = SUNDenseMatrix(p.size, p.size, ctx);
    ls = SUNLinSol_Dense(y, a, ctx);
  }
  void* mem = CVodeCreate(CV_BDF, ctx);
  CVodeInit(mem, rhs, p.t0, y);
  N_Vector atol_vector = nullptr;
  if (atols.size() > 0) {
    atol_vector = N_VNew_Serial(p.size, ctx);
    Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(atol_vector), p.size) = atols;
    CVodeSVtolerances(mem, rtol, atol_vector);
  } else {
    CVodeSStolerances(mem, rtol, atol);
  }
  CVodeSetUserData(mem, &d);
  CVodeSetLinearSolver(mem, ls, a);
  CVodeSetJacFn(mem, jacobian);
  if (projection) CVodeSetProjFn(mem, project);
  CVodeSetMaxNumSteps(mem, 10'000'000);
  CVodeSetStopTime(mem, p.t_end);
  CVodeSetMaxHnilWarns(mem, -1);  // its step-underflow warnings: reported in the note instead
  const auto start = std::chrono::steady_clock::now();
  sunrealtype t = p.t0;
  o.ok = true;
  auto failed = [&](int flag) {
    o.ok = false;
    o.note = "CVODE flag " + std::to_string(flag) + " at t = " + std::to_string(t);
  };
  if (outputs.empty()) {
    int stalled = 0;  // CVODE goes on when t + h == t; count steps that do not move
    while (t < p.t_end - 1e-12 * std::max(1.0, std::abs(p.t_end))) {
      const sunrealtype before = t;
      const int flag = CVode(mem, p.t_end, y, &t, CV_ONE_STEP);
      stalled = t == before ? stalled + 1 : 0;
      if (flag < 0) {
        failed(flag);
        break;
      }
      if (stalled > 100) {
        o.ok = false;
        o.note = "step size underflow at t = " + std::to_string(t);
        break;
      }
      if (on_output) on_output(t, N_VGetArrayPointer(y));
    }
  } else {
    for (double out : outputs) {
      const int flag = CVode(mem, out, y, &t, CV_NORMAL);
      if (flag < 0) {
        failed(flag);
        break;
      }
      if (on_output) on_output(out, N_VGetArrayPointer(y));
    }
  }
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  long nfe = 0, nst = 0, nsetups = 0;
  CVodeGetNumRhsEvals(mem, &nfe);
  CVodeGetNumSteps(mem, &nst);
  CVodeGetNumLinSolvSetups(mem, &nsetups);
  o.evaluations = nfe + d.difference_evaluations;
  o.steps = nst;
  o.jacobians = d.jacobians;
  o.setups = nsetups;
  CVodeFree(&mem);
  SUNLinSolFree(ls);
  SUNMatDestroy(a);
  N_VDestroy(y);
  if (atol_vector) N_VDestroy(atol_vector);
  SUNContext_Free(&ctx);
  return o;
}

}  // namespace mbsflow::cli
