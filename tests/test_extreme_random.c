/* Stability at the extremes (issue 6): the random initial state (the paper's
 * figure 8: free vertices uniform in the cube) at three stiffnesses, for every
 * model but `linear`; all tets uninverted at the end (the last frame). */
#define _POSIX_C_SOURCE 200809L
#include "test_extreme_util.h"

static const char *const stiff[] = {"1e4", "1e5", "1e7"};

static void recover_all(const char *model) {
  for (int i = 0; i < 3; i++) ext_recover("random_cube", model, stiff[i]);
}

Test(extreme_random, fixed_corotated, .timeout = 600) { recover_all("fixed_corotated"); }
Test(extreme_random, corotated, .timeout = 600) { recover_all("corotated"); }
Test(extreme_random, neo_hookean, .timeout = 600) { recover_all("neo_hookean"); }
Test(extreme_random, stable_neo_hookean, .timeout = 600) { recover_all("stable_neo_hookean"); }
