/* spindlebench extensions to CasADi's FMI 3.0 model-exchange wrapper (MIT-0, like the wrapper).
 *
 * CasADi exports model exchange only; this code, spliced into <model>_wrap.c by
 * spindlebench.model.fmu_export, adds
 *   - co-simulation: fmi3InstantiateCoSimulation and fmi3DoStep, integrating the generated
 *     right-hand side with an L-stable, stiffly accurate SDIRK method of order 4 (Hairer &
 *     Wanner, Solving ODEs II, table IV.6.5, "SDIRK4") with its embedded order-3 solution for
 *     error control, simplified Newton iterations on the CasADi forward-derivative Jacobian;
 *   - saved states: fmi3Get/Set/FreeFMUState and (de)serialisation, versioned;
 *   - a value-reference -> state-index table (no per-value scan of all states);
 *   - CVode callbacks in C (sb_cvode_*): an importer that drives SUNDIALS CVode itself (the
 *     spindlebench runner) gives CVode these functions instead of callbacks in its own
 *     language, hands over one input as a table on a uniform time grid (interpolated here at
 *     the solver's time) and ends each output point with one call (sb_cvode_stop).
 * Everything is sized by the generated macros (N_X, N_VAR, SZ_MEM, ...): nothing here
 * knows the model. The text between the two SB_SPLIT markers goes before CasADi's memory
 * struct (types), the rest before fmi3Reset (functions).
 */
#include <math.h>
#include <string.h>
#include <stdlib.h>

#define SB_STATE_VERSION 1
#define SB_STAGES 5
#define SB_MAX_NEWTON 10
#define SB_MIN_STEP 1e-9

/* The co-simulation integrator's memory: part of every saved FMU state, so that a run
 * restored from a saved state continues bit for bit as the uninterrupted run would. */
typedef struct {
  double h;            /* proposed next internal step (s); 0: not yet chosen */
  double tol;          /* relative tolerance (fmi3EnterInitializationMode's, or 1e-6) */
  int jac_valid;       /* J holds df/dx from an earlier point */
  double lu_hg;        /* h*gamma that LU was factorised with (0: none) */
  double J[N_X * N_X]; /* row-major: J[i*N_X + j] = d xdot_i / d x_j */
} sb_integrator;

/* Work arrays of fmi3DoStep (not part of a saved state: recomputed from sb_integrator). */
typedef struct {
  double LU[N_X * N_X];
  int piv[N_X];
  double x0[N_X], x1[N_X], f0[N_X], rhs[N_X], X[N_X], fx[N_X], dx[N_X], err[N_X];
  double K[SB_STAGES][N_X];
} sb_work;

/* What the CVode callbacks need from the importer (sb_cvode_setup, sb_cvode_table): functions
 * of its SUNDIALS (this file needs no SUNDIALS header or library: its vectors, matrices and
 * solver memory are only passed on to them), and one input as a table of values on the grid
 * t = k / rate. */
typedef double* (*sb_array_of)(void*);
typedef int (*sb_cvode_fn)(void* cvode_mem, double tout, void* yout, double* tret, int task);
typedef int (*sb_stop_time_fn)(void* cvode_mem, double tstop);
typedef int (*sb_reinit_fn)(void* cvode_mem, double t0, void* y0);
typedef struct {
  sb_array_of data_of;        /* N_VGetArrayPointer */
  sb_array_of matrix_data;    /* SUNDenseMatrix_Data (column-major) */
  sb_cvode_fn cvode;          /* CVode */
  sb_stop_time_fn stop_time;  /* CVodeSetStopTime */
  sb_reinit_fn reinit;        /* CVodeReInit */
  double* table;              /* the input at t = k / rate, k = 0 .. n-1 (n >= 2), or 0: none */
  size_t n;
  double rate;                /* 1 / the grid's step (1/s) */
  size_t offset;              /* where the input lives in the variable memory */
  int varying;                /* 0: every value equal (the loop's own setting is the value) */
} sb_host;

/* SB_SPLIT */

static const double sb_gamma = 0.25;
static const double sb_c[SB_STAGES] = {0.25, 0.75, 11.0 / 20.0, 0.5, 1.0};
static const double sb_a[SB_STAGES][SB_STAGES] = {
    {0.25, 0, 0, 0, 0},
    {0.5, 0.25, 0, 0, 0},
    {17.0 / 50.0, -1.0 / 25.0, 0.25, 0, 0},
    {371.0 / 1360.0, -137.0 / 2720.0, 15.0 / 544.0, 0.25, 0},
    {25.0 / 24.0, -49.0 / 48.0, 125.0 / 16.0, -85.0 / 12.0, 0.25}};
/* b = last row of a (stiffly accurate); the embedded order-3 weights: */
static const double sb_bhat[SB_STAGES] = {59.0 / 48.0, -17.0 / 96.0, 225.0 / 32.0,
                                          -85.0 / 12.0, 0.0};

/* A saved FMU state: everything that determines what the instance computes next. */
typedef struct {
  char magic[8];
  unsigned int version;
  unsigned int n_x, sz_mem, n_p;
  char token[40];
  double t;
  double v[SZ_MEM];
  int state_set[N_X];
  int is_cs;
  sb_integrator cs;
} sb_fmu_state;

static void sb_log(casadi_fmi_memory* m, fmi3Status status, const char* message) {
  if (m && m->sb_log) m->sb_log(m->sb_env, status, "spindlebench", message);
}

static void sb_init_extensions(casadi_fmi_memory* m) {
  size_t i;
  for (i = 0; i < N_VAR; ++i) m->sb_state_of_vr[i] = -1;
  for (i = 0; i < N_X; ++i)
    if (x_vr[i] < N_VAR) m->sb_state_of_vr[x_vr[i]] = (int)i;
  m->sb_is_cs = 0;
  m->sb_work = 0;
  m->sb_host = 0;
  memset(&m->sb_cs, 0, sizeof(m->sb_cs));
  m->sb_cs.tol = 1e-6;
}

/* xdot = f(t, x) at the instance's current inputs and parameters. */
static int sb_rhs(casadi_fmi_memory* m, double t, const double* x, double* xdot) {
  size_t i;
  m->t = t;
  for (i = 0; i < N_X; ++i) m->v[var_offset[x_vr[i]]] = x[i];
  m->up_to_date = 0;
  if (evaluate(m)) return 1;
  for (i = 0; i < N_X; ++i) xdot[i] = m->xdot[i];
  return 0;
}

/* Dense df/dx at (t, x), column by column with CasADi's forward derivative. A column with a
 * non-finite entry (automatic differentiation of a term like |dT|^(1/4)*dT at dT = 0 gives
 * inf*0) is taken by a forward difference instead: the simplified Newton iteration needs an
 * approximation of J, its result is set by the residual and the convergence test. */
static int sb_jacobian(casadi_fmi_memory* m, double t, const double* x) {
  size_t i, j;
  double* J = m->sb_cs.J;
  double f0[N_X], xp[N_X], fp[N_X];
  int finite;
  if (sb_rhs(m, t, x, f0)) return 1;
  for (j = 0; j < N_X; ++j) {
    m->d[var_offset[x_vr[j]]] = 1.0;
    if (evaluate_forward(m)) return 1;
    m->d[var_offset[x_vr[j]]] = 0.0;
    finite = 1;
    for (i = 0; i < N_X; ++i) {
      J[i * N_X + j] = m->d[var_offset[xdot_vr[i]]];
      m->d[var_offset[xdot_vr[i]]] = 0.0;
      if (!isfinite(J[i * N_X + j])) finite = 0;
    }
    for (i = 0; i < N_Y; ++i) m->d[var_offset[y_vr[i]]] = 0.0;
    if (!finite) {
      double delta = 1.4901161193847656e-08 * fmax(1.0, fabs(x[j]));
      for (i = 0; i < N_X; ++i) xp[i] = x[i];
      xp[j] += delta;
      if (sb_rhs(m, t, xp, fp)) return 1;
      for (i = 0; i < N_X; ++i) J[i * N_X + j] = (fp[i] - f0[i]) / delta;
      if (sb_rhs(m, t, x, f0)) return 1; /* the forward derivative needs the point again */
    }
  }
  m->sb_cs.jac_valid = 1;
  m->sb_cs.lu_hg = 0.0;
  return 0;
}

/* LU (partial pivoting) of I - hg*J into work->LU; 1 if singular. */
static int sb_factorise(casadi_fmi_memory* m, double hg) {
  sb_work* w = m->sb_work;
  double* A = w->LU;
  const double* J = m->sb_cs.J;
  size_t i, j, k, p;
  for (i = 0; i < N_X; ++i)
    for (j = 0; j < N_X; ++j) A[i * N_X + j] = (i == j ? 1.0 : 0.0) - hg * J[i * N_X + j];
  for (k = 0; k < N_X; ++k) {
    double best = fabs(A[k * N_X + k]);
    p = k;
    for (i = k + 1; i < N_X; ++i)
      if (fabs(A[i * N_X + k]) > best) best = fabs(A[i * N_X + k]), p = i;
    if (best == 0.0) return 1;
    w->piv[k] = (int)p;
    if (p != k)
      for (j = 0; j < N_X; ++j) {
        double tmp = A[k * N_X + j];
        A[k * N_X + j] = A[p * N_X + j];
        A[p * N_X + j] = tmp;
      }
    for (i = k + 1; i < N_X; ++i) {
      double l = A[i * N_X + k] /= A[k * N_X + k];
      if (l != 0.0)
        for (j = k + 1; j < N_X; ++j) A[i * N_X + j] -= l * A[k * N_X + j];
    }
  }
  m->sb_cs.lu_hg = hg;
  return 0;
}

static void sb_solve(const sb_work* w, double* b) {
  size_t i, j, k;
  const double* A = w->LU;
  for (k = 0; k < N_X; ++k) {
    size_t p = (size_t)w->piv[k];
    if (p != k) {
      double tmp = b[k];
      b[k] = b[p];
      b[p] = tmp;
    }
  }
  for (i = 1; i < N_X; ++i)
    for (j = 0; j < i; ++j) b[i] -= A[i * N_X + j] * b[j];
  for (i = N_X; i-- > 0;) {
    for (j = i + 1; j < N_X; ++j) b[i] -= A[i * N_X + j] * b[j];
    b[i] /= A[i * N_X + i];
  }
}

/* Weighted RMS norm: 1 is the tolerance (absolute tol in K, plus tol relative). */
static double sb_norm(const double* e, const double* xa, const double* xb, double tol) {
  size_t i;
  double sum = 0.0;
  for (i = 0; i < N_X; ++i) {
    double scale = tol + tol * fmax(fabs(xa[i]), fabs(xb[i]));
    double r = e[i] / scale;
    sum += r * r;
  }
  return sqrt(sum / (double)N_X);
}

/* One SDIRK4 step of size h from (t, w->x0); result in w->x1, error norm in *err.
 * Returns 0 (done), 1 (Newton did not converge), 2 (model evaluation failed). */
static int sb_try_step(casadi_fmi_memory* m, double t, double h, double* err_norm) {
  sb_work* w = m->sb_work;
  double hg = h * sb_gamma, tol = m->sb_cs.tol;
  size_t s, j, i;
  int it;
  if (m->sb_cs.lu_hg != hg && sb_factorise(m, hg)) return 1;
  for (s = 0; s < SB_STAGES; ++s) {
    double previous = 0.0, delta = 0.0;
    int converged = 0;
    for (i = 0; i < N_X; ++i) {
      double sum = 0.0;
      for (j = 0; j < s; ++j) sum += sb_a[s][j] * w->K[j][i];
      w->rhs[i] = w->x0[i] + h * sum;
      w->X[i] = w->rhs[i] + hg * (s == 0 ? w->f0[i] : w->K[s - 1][i]);
    }
    for (it = 0; it < SB_MAX_NEWTON; ++it) {
      if (sb_rhs(m, t + sb_c[s] * h, w->X, w->fx)) return 2;
      for (i = 0; i < N_X; ++i) w->dx[i] = w->rhs[i] + hg * w->fx[i] - w->X[i];
      sb_solve(w, w->dx);
      for (i = 0; i < N_X; ++i) w->X[i] += w->dx[i];
      delta = sb_norm(w->dx, w->X, w->x0, tol);
      if (!isfinite(delta)) break;
      if (delta <= 1e-3) {
        converged = 1;
        break;
      }
      if (it > 0) { /* contraction rate theta: the remaining error is theta/(1-theta)*delta */
        double theta = delta / previous;
        if (theta < 0.9 && theta / (1.0 - theta) * delta <= 1e-3) {
          converged = 1;
          break;
        }
      }
      if (it > 0 && delta > 0.9 * previous) break; /* diverging or too slow */
      previous = delta;
    }
    if (!converged) return 1;
    for (i = 0; i < N_X; ++i) w->K[s][i] = (w->X[i] - w->rhs[i]) / hg;
  }
  for (i = 0; i < N_X; ++i) {
    double e = 0.0;
    for (s = 0; s < SB_STAGES; ++s) e += (sb_a[SB_STAGES - 1][s] - sb_bhat[s]) * w->K[s][i];
    w->x1[i] = w->X[i];
    w->err[i] = h * e;
  }
  sb_solve(w, w->err); /* filter the stiff components (Hairer & Wanner IV.8) */
  *err_norm = sb_norm(w->err, w->x0, w->x1, tol);
  return 0;
}

static fmi3Status sb_do_step(casadi_fmi_memory* m, double t0, double step) {
  sb_work* w;
  sb_integrator* cs = &m->sb_cs;
  double t = t0, t_end = t0 + step, h, err;
  size_t i;
  int fresh = 0, flag;
  if (!m->sb_is_cs) {
    sb_log(m, fmi3Error, "fmi3DoStep: instance was not instantiated for co-simulation");
    return fmi3Error;
  }
#if N_ZERO > 0
  /* the integrator has no event location: a model with zero crossings is refused here
   * rather than stepped over its events (model exchange handles them) */
  sb_log(m, fmi3Error, "fmi3DoStep: co-simulation of a model with event indicators is not "
         "implemented (use model exchange)");
  return fmi3Error;
#endif
  if (step <= 0.0) return step == 0.0 ? fmi3OK : fmi3Error;
  if (!m->sb_work) {
    m->sb_work = (sb_work*)calloc(1, sizeof(sb_work));
    if (!m->sb_work) return fmi3Fatal;
    if (cs->lu_hg != 0.0 && sb_factorise(m, cs->lu_hg)) cs->lu_hg = 0.0;
  }
  w = m->sb_work;
  for (i = 0; i < N_X; ++i) w->x0[i] = m->v[var_offset[x_vr[i]]];
  if (sb_rhs(m, t, w->x0, w->f0)) return fmi3Error;
  if (cs->h <= 0.0) {
    /* first step: a change of about tol relative to the fastest rate, within the step */
    double rate = sb_norm(w->f0, w->x0, w->x0, cs->tol);
    cs->h = rate > 0 ? fmin(step, 0.1 / rate) : step;
    if (cs->h < SB_MIN_STEP) cs->h = SB_MIN_STEP;
  }
  if (!cs->jac_valid) {
    if (sb_jacobian(m, t, w->x0)) return fmi3Error;
    fresh = 1;
  }
  while (t < t_end) {
    int last = 0;
    h = cs->h;
    if (t + h >= t_end - 1e-12 * fmax(1.0, fabs(t_end))) {
      h = t_end - t;
      last = 1;
    }
    /* keep the factorisation when the step changes by less than 20 % (Hairer's rule) */
    if (!last && cs->lu_hg != 0.0 && h >= cs->lu_hg / sb_gamma && h <= 1.2 * cs->lu_hg / sb_gamma)
      h = cs->lu_hg / sb_gamma;
    flag = sb_try_step(m, t, h, &err);
    if (flag == 2) {
      sb_log(m, fmi3Error, "fmi3DoStep: the model evaluation failed");
      return fmi3Error;
    }
    if (flag == 1) { /* Newton failed: fresh Jacobian first, then a smaller step */
      if (!fresh) {
        if (sb_jacobian(m, t, w->x0)) return fmi3Error;
        fresh = 1;
      } else {
        cs->h = 0.25 * h;
      }
      if (cs->h < SB_MIN_STEP) {
        sb_log(m, fmi3Error, "fmi3DoStep: step size below 1e-9 s (Newton iterations fail)");
        return fmi3Error;
      }
      continue;
    }
    if (err <= 1.0) {
      double factor = err > 0 ? 0.9 * pow(err, -0.25) : 5.0;
      t = last ? t_end : t + h;
      for (i = 0; i < N_X; ++i) w->x0[i] = w->x1[i];
      if (t < t_end && sb_rhs(m, t, w->x0, w->f0)) return fmi3Error;
      factor = fmin(5.0, fmax(1.0, factor));
      /* a step shortened to meet the communication point keeps the proposed size */
      if (!last || h * factor > cs->h) cs->h = h * factor;
      fresh = 0;
    } else {
      cs->h = h * fmax(0.2, 0.9 * pow(err, -0.25));
      if (cs->h < SB_MIN_STEP) {
        sb_log(m, fmi3Error, "fmi3DoStep: step size below 1e-9 s (error test fails)");
        return fmi3Error;
      }
    }
  }
  for (i = 0; i < N_X; ++i) m->v[var_offset[x_vr[i]]] = w->x0[i];
  m->t = t_end;
  m->up_to_date = 0;
  return fmi3OK;
}

static void sb_capture(const casadi_fmi_memory* m, sb_fmu_state* s) {
  memset(s, 0, sizeof(*s));
  memcpy(s->magic, "SBFMUST", 8);
  s->version = SB_STATE_VERSION;
  s->n_x = N_X;
  s->sz_mem = SZ_MEM;
  s->n_p = N_P;
  strncpy(s->token, SB_TOKEN, sizeof(s->token) - 1);
  s->t = m->t;
  memcpy(s->v, m->v, sizeof(s->v));
  memcpy(s->state_set, m->state_set, sizeof(s->state_set));
  s->is_cs = m->sb_is_cs;
  memcpy(&s->cs, &m->sb_cs, sizeof(s->cs));
}

static fmi3Status sb_check_state(casadi_fmi_memory* m, const sb_fmu_state* s) {
  if (memcmp(s->magic, "SBFMUST", 8) != 0) {
    sb_log(m, fmi3Error, "not a SpindleBench FMU state");
    return fmi3Error;
  }
  if (s->version != SB_STATE_VERSION) {
    sb_log(m, fmi3Error, "FMU state of another format version");
    return fmi3Error;
  }
  if (s->n_x != N_X || s->sz_mem != SZ_MEM || s->n_p != N_P ||
      strncmp(s->token, SB_TOKEN, sizeof(s->token)) != 0) {
    sb_log(m, fmi3Error, "FMU state saved by another build of the model");
    return fmi3Error;
  }
  return fmi3OK;
}

static fmi3Status sb_get_state(casadi_fmi_memory* m, fmi3FMUState* state) {
  sb_fmu_state* s = *state ? (sb_fmu_state*)*state : (sb_fmu_state*)malloc(sizeof(*s));
  if (!s) return fmi3Error;
  sb_capture(m, s);
  *state = s;
  return fmi3OK;
}

static fmi3Status sb_set_state(casadi_fmi_memory* m, fmi3FMUState state) {
  const sb_fmu_state* s = (const sb_fmu_state*)state;
  if (!s || sb_check_state(m, s) != fmi3OK) return fmi3Error;
  m->t = s->t;
  memcpy(m->v, s->v, sizeof(m->v));
  memcpy(m->state_set, s->state_set, sizeof(m->state_set));
  memcpy(&m->sb_cs, &s->cs, sizeof(m->sb_cs));
  m->up_to_date = 0;
  /* the factorisation is recomputed from J and h*gamma: the same bytes as the saved run's */
  if (m->sb_work && m->sb_cs.lu_hg != 0.0 && sb_factorise(m, m->sb_cs.lu_hg))
    m->sb_cs.lu_hg = 0.0;
  return fmi3OK;
}

static fmi3Status sb_free_state(fmi3FMUState* state) {
  if (state && *state) {
    free(*state);
    *state = 0;
  }
  return fmi3OK;
}

static fmi3Status sb_serialize(casadi_fmi_memory* m, fmi3FMUState state, fmi3Byte* out,
                               size_t size) {
  if (!state || size != sizeof(sb_fmu_state)) {
    sb_log(m, fmi3Error, "fmi3SerializeFMUState: wrong buffer size");
    return fmi3Error;
  }
  memcpy(out, state, sizeof(sb_fmu_state));
  return fmi3OK;
}

static fmi3Status sb_deserialize(casadi_fmi_memory* m, const fmi3Byte* in, size_t size,
                                 fmi3FMUState* state) {
  sb_fmu_state* s;
  if (size != sizeof(sb_fmu_state)) {
    sb_log(m, fmi3Error, "fmi3DeserializeFMUState: size does not match this model build");
    return fmi3Error;
  }
  s = (sb_fmu_state*)malloc(sizeof(*s)); /* aligned copy before reading any field */
  if (!s) return fmi3Error;
  memcpy(s, in, sizeof(*s));
  if (sb_check_state(m, s) != fmi3OK) {
    free(s);
    return fmi3Error;
  }
  if (*state) { /* an existing state is overwritten (FMI 3.0, 2.2.6.4) */
    memcpy(*state, s, sizeof(*s));
    free(s);
  } else {
    *state = s;
  }
  return fmi3OK;
}


/* ---------------------------------------------------------------- CVode callbacks in C
 * The right-hand side an importer gives CVode (CVodeInit) with the instance as user data
 * (CVodeSetUserData): the same work as its own callback doing fmi3SetTime, setting the table's
 * input, fmi3SetContinuousStates and fmi3GetContinuousStateDerivatives, in the same floating
 * point operations, so the results are the same bytes, without a call into the importer's
 * language per evaluation (CVode's difference-quotient Jacobian calls it N_X times too). */

#if defined(__GNUC__)
#define SB_EXPORT __attribute__((visibility("default")))
#else
#define SB_EXPORT
#endif

/* Give the instance the importer's SUNDIALS functions (N_VGetArrayPointer, SUNDenseMatrix_Data,
 * CVode, CVodeSetStopTime, CVodeReInit; only the first is needed by sb_cvode_rhs and
 * sb_cvode_stop). 0 OK, 1 no N_VGetArrayPointer or no memory. */
SB_EXPORT int sb_cvode_setup(fmi3Instance instance, void* n_v_get_array_pointer,
                             void* dense_matrix_data, void* cvode, void* set_stop_time,
                             void* reinit) {
  casadi_fmi_memory* m = (casadi_fmi_memory*)instance;
  sb_host* h;
  if (!m || !n_v_get_array_pointer) return 1;
  if (!m->sb_host) m->sb_host = (sb_host*)calloc(1, sizeof(sb_host));
  if (!m->sb_host) return 1;
  h = m->sb_host;
  h->data_of = (sb_array_of)n_v_get_array_pointer;
  h->matrix_data = (sb_array_of)dense_matrix_data;
  h->cvode = (sb_cvode_fn)cvode;
  h->stop_time = (sb_stop_time_fn)set_stop_time;
  h->reinit = (sb_reinit_fn)reinit;
  return 0;
}

/* One input (value reference vr) as n >= 2 values on the grid t = k * step_s, copied; between
 * grid points the right-hand side interpolates linearly. n = 0 removes the table. 0 OK, 1 bad
 * arguments (no sb_cvode_setup, not a Float64 scalar, n = 1, step <= 0), 2 no memory. */
SB_EXPORT int sb_cvode_table(fmi3Instance instance, fmi3ValueReference vr,
                             const double* values, size_t n, double step_s) {
  casadi_fmi_memory* m = (casadi_fmi_memory*)instance;
  sb_host* h = m ? m->sb_host : 0;
  size_t i;
  if (!h) return 1;
  free(h->table);
  h->table = 0;
  h->n = 0;
  if (n == 0) return 0;
  if (n < 2 || !values || !(step_s > 0) || vr >= N_VAR ||
      var_offset[vr + 1] - var_offset[vr] != 1)
    return 1;
  h->table = (double*)malloc(n * sizeof(double));
  if (!h->table) return 2;
  memcpy(h->table, values, n * sizeof(double));
  h->n = n;
  h->rate = 1.0 / step_s;
  h->offset = var_offset[vr];
  h->varying = 0;
  for (i = 1; i < n; ++i)
    if (values[i] != values[0]) h->varying = 1;
  return 0;
}

/* The instance at time t: the time, and the table's input interpolated there. */
static void sb_at_time(casadi_fmi_memory* m, double t) {
  const sb_host* h = m->sb_host;
  m->t = t;
  if (h->table && h->varying) {
    double x = t * h->rate;
    size_t last = h->n - 2, k = x > 0 ? (size_t)x : 0; /* (size_t)x truncates like int(x) */
    const double* a = h->table;
    if (k > last) k = last;
    m->v[h->offset] = a[k] + (x - (double)k) * (a[k + 1] - a[k]);
  }
  m->up_to_date = 0;
}

/* CVRhsFn: ydot = f(t, y), user_data = the instance. 0 OK, 1 the model evaluation failed
 * (CVode retries with a smaller step, then gives up), -1 not set up. */
SB_EXPORT int sb_cvode_rhs(double t, void* y, void* ydot, void* user_data) {
  casadi_fmi_memory* m = (casadi_fmi_memory*)user_data;
  const double* x;
  double* xdot;
  size_t i;
  if (!m || !m->sb_host || !m->sb_host->data_of) return -1;
  x = m->sb_host->data_of(y);
  xdot = m->sb_host->data_of(ydot);
  sb_at_time(m, t);
  if (fmi3SetContinuousStates(m, x, N_X) != fmi3OK) return -1;
  if (evaluate(m)) return 1;
  m->up_to_date = 1;
  for (i = 0; i < N_X; ++i) xdot[i] = m->xdot[i];
  return 0;
}

/* The end of one solver segment at time t: the states CVode returned (y), the inputs valid
 * from t on (n_in values for the value references in_vr) and, with out non-null, the n_out
 * outputs (value references out_vr) evaluated there, once. The same calls an importer makes
 * (fmi3SetContinuousStates, fmi3SetTime, fmi3SetFloat64, fmi3GetFloat64), in one.
 * Returns an fmi3Status. */
SB_EXPORT int sb_cvode_stop(fmi3Instance instance, double t, void* y,
                            const fmi3ValueReference in_vr[], size_t n_in, const double u[],
                            const fmi3ValueReference out_vr[], size_t n_out, double out[]) {
  casadi_fmi_memory* m = (casadi_fmi_memory*)instance;
  fmi3Status status;
  if (!m || !m->sb_host || !m->sb_host->data_of) return fmi3Error;
  status = fmi3SetContinuousStates(m, m->sb_host->data_of(y), N_X);
  if (status != fmi3OK) return status;
  m->t = t;
  status = fmi3SetFloat64(m, in_vr, n_in, u, n_in);
  if (status != fmi3OK || !out) return status;
  return fmi3GetFloat64(m, out_vr, n_out, out, n_out);
}

/* The structure of d xdot / d x (SB_JAC_*: generated by spindlebench.model.fmu_export from the
 * model description's dependencies, CasADi's sparsity) and a colouring of its columns: no two
 * columns of one colour share a row, so one forward derivative per colour gives them all. */
@SB_JACOBIAN_STRUCTURE@

/* CVLsJacFn: the dense Jacobian J = d f / d y at (t, y), fy = f(t, y), user_data = the
 * instance. One CasADi forward derivative per colour; a column with a non-finite entry
 * (automatic differentiation of |dT|^(1/4)*dT at dT = 0 gives inf*0) is a forward difference
 * on fy instead. 0 OK, 1 the model evaluation failed, -1 not set up or a mismatched table. */
SB_EXPORT int sb_cvode_jac(double t, void* y, void* fy, void* jac, void* user_data, void* tmp1,
                           void* tmp2, void* tmp3) {
  casadi_fmi_memory* m = (casadi_fmi_memory*)user_data;
  const double *x, *f0;
  double *J, *xp, *fp;
  size_t i, j, e;
  int c;
  if (!m || !m->sb_host || !m->sb_host->data_of || !m->sb_host->matrix_data) return -1;
  for (j = 0; j < N_X; ++j)
    if (sb_jac_state_vr[j] != x_vr[j]) return -1;
  x = m->sb_host->data_of(y);
  f0 = m->sb_host->data_of(fy);
  xp = m->sb_host->data_of(tmp1);
  fp = m->sb_host->data_of(tmp2);
  (void)tmp3;
  J = m->sb_host->matrix_data(jac);
  for (e = 0; e < (size_t)N_X * N_X; ++e) J[e] = 0.0;
  sb_at_time(m, t);
  if (fmi3SetContinuousStates(m, x, N_X) != fmi3OK) return -1;
  if (evaluate(m)) return 1;
  m->up_to_date = 1;
  for (c = 0; c < SB_JAC_COLORS; ++c) {
    for (j = 0; j < N_X; ++j)
      if (sb_jac_color[j] == c) m->d[var_offset[x_vr[j]]] = 1.0;
    if (evaluate_forward(m)) return 1;
    for (j = 0; j < N_X; ++j) {
      if (sb_jac_color[j] != c) continue;
      m->d[var_offset[x_vr[j]]] = 0.0;
      for (e = sb_jac_colstart[j]; e < sb_jac_colstart[j + 1]; ++e) {
        i = sb_jac_row[e];
        J[j * N_X + i] = m->d[var_offset[xdot_vr[i]]];
      }
    }
    for (i = 0; i < N_X; ++i) m->d[var_offset[xdot_vr[i]]] = 0.0;
    for (i = 0; i < N_Y; ++i) m->d[var_offset[y_vr[i]]] = 0.0;
  }
  for (j = 0; j < N_X; ++j) {
    int finite = 1;
    double delta;
    for (i = 0; i < N_X; ++i)
      if (!isfinite(J[j * N_X + i])) finite = 0;
    if (finite) continue;
    delta = 1.4901161193847656e-08 * fmax(1.0, fabs(x[j]));
    for (i = 0; i < N_X; ++i) xp[i] = x[i];
    xp[j] += delta;
    if (fmi3SetContinuousStates(m, xp, N_X) != fmi3OK) return -1;
    m->up_to_date = 0;
    if (evaluate(m)) return 1;
    for (i = 0; i < N_X; ++i) fp[i] = m->xdot[i];
    for (i = 0; i < N_X; ++i) J[j * N_X + i] = (fp[i] - f0[i]) / delta;
  }
  return 0;
}

/* CVLsJacFn like sb_cvode_jac, from difference quotients on fy: all columns of one colour
 * perturbed at once, each by sqrt(eps) * max(|y_j|, 1) (the rows a column reaches are reached by
 * no other column of its colour), one right-hand side per colour instead of one per column.
 * 0 OK, 1 the model evaluation failed, -1 not set up or a mismatched table. */
SB_EXPORT int sb_cvode_jac_dq(double t, void* y, void* fy, void* jac, void* user_data,
                              void* tmp1, void* tmp2, void* tmp3) {
  casadi_fmi_memory* m = (casadi_fmi_memory*)user_data;
  const double *x, *f0;
  double *J, *xp, *inc;
  size_t i, j, e;
  int c;
  if (!m || !m->sb_host || !m->sb_host->data_of || !m->sb_host->matrix_data) return -1;
  for (j = 0; j < N_X; ++j)
    if (sb_jac_state_vr[j] != x_vr[j]) return -1;
  x = m->sb_host->data_of(y);
  f0 = m->sb_host->data_of(fy);
  xp = m->sb_host->data_of(tmp1);
  inc = m->sb_host->data_of(tmp2);
  (void)tmp3;
  J = m->sb_host->matrix_data(jac);
  for (e = 0; e < (size_t)N_X * N_X; ++e) J[e] = 0.0;
  for (j = 0; j < N_X; ++j) inc[j] = 1.4901161193847656e-08 * fmax(1.0, fabs(x[j]));
  for (c = 0; c < SB_JAC_COLORS; ++c) {
    for (j = 0; j < N_X; ++j) xp[j] = sb_jac_color[j] == c ? x[j] + inc[j] : x[j];
    sb_at_time(m, t);
    if (fmi3SetContinuousStates(m, xp, N_X) != fmi3OK) return -1;
    if (evaluate(m)) return 1;
    for (j = 0; j < N_X; ++j) {
      double h;
      if (sb_jac_color[j] != c) continue;
      h = xp[j] - x[j]; /* the increment as represented */
      for (e = sb_jac_colstart[j]; e < sb_jac_colstart[j + 1]; ++e) {
        i = sb_jac_row[e];
        J[j * N_X + i] = (m->xdot[i] - f0[i]) / h;
      }
    }
  }
  m->up_to_date = 0;
  return 0;
}

/* The loop between output points, in C: for stops first .. first+count-1, CVode to
 * stop[s] * step_s without passing end[s] * step_s, then sb_cvode_stop with the input row
 * stop[s] (rows of n_in values, the input value references in_vr) and, where stop[s] is a
 * multiple of every, the outputs into row stop[s] / every of samples; CVodeReInit where
 * jump[stop[s]]. Needs sb_cvode_setup's CVode functions. Returns 0, or where it failed:
 * 1 CVode (its flag in *flag), 2 CVode stopped elsewhere (*t_reached), 3 the FMU (the FMI
 * status in *flag), 4 CVodeReInit (*flag), -1 not set up. *done: the stops completed. */
SB_EXPORT int sb_cvode_run(fmi3Instance instance, void* cvode_mem, void* y,
                           const long long* stop, const long long* end,
                           const unsigned char* jump, size_t first, size_t count, double step_s,
                           long long every, const fmi3ValueReference in_vr[], size_t n_in,
                           const double* inputs, const fmi3ValueReference out_vr[],
                           size_t n_out, double* samples, size_t* done, int* flag,
                           double* t_reached) {
  casadi_fmi_memory* m = (casadi_fmi_memory*)instance;
  const sb_host* h = m ? m->sb_host : 0;
  size_t s;
  *done = 0;
  if (!h || !h->cvode || !h->stop_time || !h->reinit) return -1;
  for (s = first; s < first + count; ++s) {
    long long k = stop[s];
    double t_next = (double)k * step_s, t = 0.0;
    *flag = h->stop_time(cvode_mem, (double)end[s] * step_s);
    if (*flag < 0) return 1;
    *flag = h->cvode(cvode_mem, t_next, y, &t, 1 /* CV_NORMAL */);
    *t_reached = t;
    if (*flag < 0) return 1;
    if (fabs(t - t_next) > 1e-9 * fmax(1.0, t_next)) return 2;
    *flag = sb_cvode_stop(m, t_next, y, in_vr, n_in, inputs + (size_t)k * n_in, out_vr, n_out,
                          k % every == 0 ? samples + (size_t)(k / every) * n_out : 0);
    if (*flag != fmi3OK) return 3;
    if (jump[k]) {
      *flag = h->reinit(cvode_mem, t_next, y);
      if (*flag < 0) return 4;
    }
    *done = s - first + 1;
  }
  return 0;
}
