/* test_term_eval.h — a term's value, gradient and Hessian for tests that call
 * its ops directly: each asserts that the term returned BS_TERM_OK (a test
 * that expects BS_TERM_NOT_EVALUABLE calls the ops itself). Include after
 * criterion. */
#ifndef BS_TEST_TERM_EVAL_H
#define BS_TEST_TERM_EVAL_H

#include <math.h>

#include "bs_terms.h"

/* E(x). */
static inline double term_value(const bs_term *t, const double *x) {
  double E = NAN;
  int rc = t->ops->value(t, x, &E);
  cr_assert_eq(rc, BS_TERM_OK, "%s: value returned %s", t->name, bs_term_status_name((bs_term_status)rc));
  return E;
}

/* E(x), with grad E(x) added into g. */
static inline double term_gradient(const bs_term *t, const double *x, double *g) {
  double E = NAN;
  int rc = t->ops->gradient(t, x, &E, g);
  cr_assert_eq(rc, BS_TERM_OK, "%s: gradient returned %s", t->name, bs_term_status_name((bs_term_status)rc));
  return E;
}

/* Hessian at x added into H. */
static inline void term_hessian(const bs_term *t, const double *x, bs_bsr *H) {
  int rc = t->ops->hessian(t, x, H);
  cr_assert_eq(rc, BS_TERM_OK, "%s: hessian returned %s", t->name, bs_term_status_name((bs_term_status)rc));
}

#endif
