"""The C API of the generated hybrid loop: NULL pointers, out-of-range arguments and parameters, and starts beyond a wall
are refused with the documented codes (never a crash), and the example program parses its arguments."""
import re
import subprocess

import numpy as np
import pytest

from codegen.pipeline import write_model, write_standalone
from runtime.compile import copy_library, library_sources
from conftest import sanitized_build
from runtime.header import return_codes
from codegen.scene import load_scene
from runtime import simulate


# One case per run of the driver (a crash fails only that case).  Each prints "code=<n>" and, where it
# checks more, "same=<0|1>" (a result compared with another run) or "msg=<error message>".
DRIVER = r"""
#include "paper_case1.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef paper_case1_sim sim_t;

/* Run to t_end from an initialised sim; the number of impacts, or an error code (< 0). */
static long run_to(sim_t *sim, double t_end)
{
    paper_case1_impact_record rec;
    long impacts = 0;
    int code;
    while ((code = paper_case1_sim_advance(sim, t_end, NULL, 0, NULL, NULL, &rec)) == GAC_SIM_IMPACT
           || code == GAC_SIM_CONTACT) {
        if (code == GAC_SIM_IMPACT) ++impacts;
    }
    return code == GAC_SIM_END ? impacts : code;
}

/* 1 if two sims reached bitwise the same state with the same impacts. */
static int same_run(sim_t *a, sim_t *b, double t_end)
{
    long na = run_to(a, t_end), nb = run_to(b, t_end);
    return na == nb && na > 0 && a->base.t == b->base.t
           && memcmp(a->base.x, b->base.x, PAPER_CASE1_NX * sizeof(double)) == 0;
}

/* q moved along X2 so that the lowest point on the floor x2_min has the gap -depth. */
static void lower_to(double *q, const double *p, double depth)
{
    double gaps[PAPER_CASE1_NCONTACT], lowest = 1e300;
    int c, point, axis, sign;
    paper_case1_contact_gaps(q, p, gaps);
    for (c = 0; c < PAPER_CASE1_NCONTACT; ++c) {
        paper_case1_contact_info(c, &point, &axis, &sign);
        if (axis == 1 && sign > 0 && gaps[c] < lowest) lowest = gaps[c];
    }
    q[PAPER_CASE1_Q_X2] -= lowest + depth;
}

int main(int argc, char **argv)
{
    static sim_t sim, other;
    paper_case1_options opt;
    paper_case1_impact_record rec;
    double p[PAPER_CASE1_NPARAM], q[PAPER_CASE1_NQ], qd[PAPER_CASE1_NQ];
    double t_eval[2] = {0.1, 0.2}, x_eval[2 * PAPER_CASE1_NX];
    int i_eval = 0, code = 0;
    const char *c = argc > 1 ? argv[1] : "";
    paper_case1_default_options(&opt);
    paper_case1_default_parameters(p);
    paper_case1_initial_state(q, qd);
    if (strcmp(c, "init_null_sim") == 0) code = paper_case1_sim_init(NULL, 0.0, q, qd, p, &opt);
    else if (strcmp(c, "init_null_q") == 0) code = paper_case1_sim_init(&sim, 0.0, NULL, qd, p, &opt);
    else if (strcmp(c, "init_null_qd") == 0) code = paper_case1_sim_init(&sim, 0.0, q, NULL, p, &opt);
    else if (strcmp(c, "init_nan_q") == 0) {
        q[0] = NAN;
        code = paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);
    } else if (strcmp(c, "init_bad_method") == 0) {
        opt.method = 7;
        code = paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);
    } else if (strcmp(c, "init_rtol_below_min") == 0 || strcmp(c, "init_rtol_at_min") == 0
               || strcmp(c, "init_rtol_one") == 0) {
        opt.rtol = strcmp(c, "init_rtol_below_min") == 0 ? 0.99 * GAC_RTOL_MIN
                   : strcmp(c, "init_rtol_one") == 0 ? 1.0 : GAC_RTOL_MIN;
        code = paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);
    } else if (strcmp(c, "init_null_opt") == 0 || strcmp(c, "init_null_p") == 0) {
        const int null_opt = strcmp(c, "init_null_opt") == 0;
        code = paper_case1_sim_init(&sim, 0.0, q, qd, null_opt ? p : NULL, null_opt ? NULL : &opt);
        if (paper_case1_sim_init(&other, 0.0, q, qd, p, &opt) != GAC_OK) return 3;
        printf("same=%d\n", code == GAC_OK && same_run(&sim, &other, 1.5));
    } else if (strcmp(c, "init_bad_restitution") == 0 || strcmp(c, "init_walls_crossed") == 0) {
        int bad = -1;
        if (strcmp(c, "init_bad_restitution") == 0) p[PAPER_CASE1_P_E_X2_MIN] = -0.5;
        else p[PAPER_CASE1_P_WALL_X1_MIN] = 4.0;                  /* beyond x1_max = 3 */
        memset(&sim, 0xab, sizeof sim);
        memset(&other, 0xab, sizeof other);
        code = paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);
        printf("same=%d\n", memcmp(&sim, &other, sizeof sim) == 0 && paper_case1_check_parameters(p, &bad) == code);
        printf("name=%s\n", bad >= 0 ? paper_case1_model.parameter_info[bad].name : "");
        printf("msg=%s\n", bad >= 0 ? paper_case1_model.parameter_info[bad].range : "");
    } else if (strcmp(c, "floor") == 0 && argc == 4) {   /* floor <depth below x2_min> <contact_tol> */
        opt.contact_tol = strtod(argv[3], NULL);
        lower_to(q, p, strtod(argv[2], NULL));
        code = paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);
        if (code == GAC_OK) {                    /* and the loop runs from there */
            long n = run_to(&sim, 0.5);
            if (n < 0) code = (int)n;
        }
        printf("msg=%s\n", paper_case1_error_message(code));
    } else if (strcmp(c, "init_error_leaves_sim") == 0) {
        memset(&sim, 0xab, sizeof sim);
        memset(&other, 0xab, sizeof other);
        lower_to(q, p, 1e-3);
        code = paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);
        printf("same=%d\n", memcmp(&sim, &other, sizeof sim) == 0);
    } else if (strcmp(c, "copy") == 0) {            /* copies bound to their own storage run on alone */
        static paper_case1_impact_record copy;
        int bound, equal;
        code = paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);
        if (paper_case1_sim_advance(&sim, 1.0, NULL, 0, NULL, NULL, &rec) != GAC_SIM_IMPACT) return 3;
        paper_case1_sim_copy(&other, &sim);
        paper_case1_impact_record_copy(&copy, &rec);
        bound = other.base.x == other.dwork && other.base.x != sim.base.x && copy.base.impulse != rec.base.impulse
                && copy.base.contact == copy.iwork;
        equal = copy.base.t == rec.base.t && copy.base.ncontact == rec.base.ncontact
                && copy.base.impulse[0] == rec.base.impulse[0] && copy.base.contact[0] == rec.base.contact[0];
        memset(&rec, 0, sizeof rec);                  /* the original record gone: the copy keeps its data */
        equal = equal && copy.base.impulse[0] != 0.0;
        printf("same=%d\n", bound && equal && same_run(&sim, &other, 1.5));
    } else if (strcmp(c, "sens") == 0) {            /* sensitivities through the per-model wrappers */
        static double sdw[PAPER_CASE1_SENS_NDOUBLE(2)], seed_x[2 * PAPER_CASE1_NX], seed_p[2 * PAPER_CASE1_NPARAM];
        double S[2 * PAPER_CASE1_NX];
        gac_sens sens;
        int i;
        memset(seed_x, 0, sizeof seed_x);
        memset(seed_p, 0, sizeof seed_p);
        seed_x[PAPER_CASE1_NQ + PAPER_CASE1_Q_X1] = 1.0;                    /* d / d qd0[X1] */
        seed_p[PAPER_CASE1_NPARAM + PAPER_CASE1_P_G] = 1.0;                 /* d / d g */
        code = paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);
        if (code != GAC_OK || paper_case1_sens_state(&sim, S) != GAC_ERR_NULL_ARGUMENT) return 3;   /* none yet */
        if (paper_case1_sens_attach(&sim, &sens, 0, seed_x, seed_p, sdw) != GAC_ERR_BAD_OPTION) return 5;
        code = paper_case1_sens_attach(&sim, &sens, 2, seed_x, seed_p, sdw);
        if (code != GAC_OK) return 6;
        while ((code = paper_case1_sim_advance(&sim, 0.6, NULL, 0, NULL, NULL, &rec)) == GAC_SIM_IMPACT
               || code == GAC_SIM_CONTACT) {
        }
        if (code != GAC_SIM_END) return 3;
        code = paper_case1_sens_state(&sim, S);
        printf("status=%d\nimpacts=%ld\n", sens.status, sens.n_impacts);
        printf("S=");
        for (i = 0; i < 2 * PAPER_CASE1_NX; ++i) printf("%.17g%s", S[i], i + 1 < 2 * PAPER_CASE1_NX ? "," : "\n");
    } else if (strcmp(c, "state_null") == 0) {
        double t = -1.0, v[PAPER_CASE1_NQ];
        code = paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt);
        paper_case1_default_options(NULL);
        paper_case1_sim_state(NULL, &t, q, qd);
        paper_case1_sim_state(&sim, NULL, NULL, NULL);
        paper_case1_sim_state(&sim, &t, NULL, v);
        printf("same=%d\n", t == 0.0 && memcmp(v, qd, sizeof v) == 0);
    } else if (strncmp(c, "adv_", 4) == 0) {
        double t_end = 1.0;
        int n_eval = 2;
        const double *te = t_eval;
        double *xe = x_eval;
        int *ie = &i_eval;
        paper_case1_impact_record *r = &rec;
        sim_t *s = &sim;
        if (paper_case1_sim_init(&sim, 0.0, q, qd, p, &opt) != GAC_OK) return 3;
        if (strcmp(c, "adv_null_sim") == 0) s = NULL;
        else if (strcmp(c, "adv_null_record") == 0) r = NULL;
        else if (strcmp(c, "adv_null_t_eval") == 0) te = NULL;
        else if (strcmp(c, "adv_null_x_eval") == 0) xe = NULL;
        else if (strcmp(c, "adv_null_i_eval") == 0) ie = NULL;
        else if (strcmp(c, "adv_n_eval_negative") == 0) n_eval = -1;
        else if (strcmp(c, "adv_i_eval_negative") == 0) i_eval = -1;
        else if (strcmp(c, "adv_i_eval_past_n_eval") == 0) i_eval = 3;
        else if (strcmp(c, "adv_t_end_inf") == 0) t_end = INFINITY;
        else if (strcmp(c, "adv_t_end_nan") == 0) t_end = NAN;
        else if (strcmp(c, "adv_t_end_before_t") == 0) {
            if (paper_case1_sim_advance(&sim, 0.1, NULL, 0, NULL, NULL, &rec) != GAC_SIM_END) return 3;
            t_end = 0.05;
        } else if (strcmp(c, "adv_no_samples_null") == 0) {
            n_eval = 0;
            te = NULL;
            xe = NULL;
            ie = NULL;
        } else if (strcmp(c, "adv_ok") != 0) return 4;
        code = paper_case1_sim_advance(s, t_end, te, n_eval, ie, xe, r);
        if (code < 0) {          /* a refused call changes nothing: a valid one carries on as from the start */
            i_eval = 0;
            if (paper_case1_sim_init(&other, 0.0, q, qd, p, &opt) != GAC_OK) return 3;
            printf("same=%d\n", same_run(&sim, &other, 1.5) || strcmp(c, "adv_t_end_before_t") == 0);
        }
        printf("msg=%s\n", paper_case1_error_message(code));
    } else return 4;
    printf("code=%d\n", code);
    return 0;
}
"""


def code_of(built, suffix: str) -> int:
    """The value of GAC_<suffix>, read from the compiled library (not from header text)."""
    return int(getattr(built[1].lib, f"GAC_{suffix}"))


@pytest.fixture(scope="module")
def built(tmp_path_factory, compiled):
    """paper-case1 generated with its standalone example; the API driver and the example compiled with the
    library; and the compiled Python module of the same model."""
    out = tmp_path_factory.mktemp("c_api")
    scene = load_scene("paper-case1")
    compiled_model = compiled(scene, specialise=True, tangent=True)   # with the tangent kernels: sensitivities
    model = compiled_model.generated                      # the suite's model of the scene, derived once
    write_model(model, out)
    copy_library(out)
    write_standalone(model, scene, out, [path.name for path in library_sources()])
    (out / "driver.c").write_text(DRIVER)
    sanitized_build(out, [out / "paper_case1.c", out / "driver.c"], "driver")
    sanitized_build(out, [out / "paper_case1.c", out / "paper_case1_example.c"], "example")
    return out, compiled_model


def drive(built, *args) -> dict:
    out, _ = built
    result = subprocess.run([str(out / "driver"), *map(str, args)], capture_output=True, text=True)
    assert result.returncode == 0, f"driver {args} crashed or failed ({result.returncode}): {result.stderr}"
    return dict(line.split("=", 1) for line in result.stdout.splitlines())


@pytest.mark.parametrize("case,expected", [
    ("init_null_sim", "ERR_NULL_ARGUMENT"),
    ("init_null_q", "ERR_NULL_ARGUMENT"),
    ("init_null_qd", "ERR_NULL_ARGUMENT"),
    ("init_nan_q", "ERR_BAD_OPTION"),
    ("init_bad_method", "ERR_BAD_OPTION"),
    ("init_rtol_below_min", "ERR_BAD_OPTION"),
    ("init_rtol_one", "ERR_BAD_OPTION"),
])
def test_sim_init_refuses_bad_arguments(built, case, expected):
    assert int(drive(built, case)["code"]) == code_of(built, expected)


def test_sim_init_accepts_the_smallest_rtol(built):
    assert int(drive(built, "init_rtol_at_min")["code"]) == 0


@pytest.mark.parametrize("case,name,rule", [
    ("init_bad_restitution", "e_x2_min", "restitution must be in [0, 1]"),
    ("init_walls_crossed", "wall_x1_max", "must be within [-1e+09, 1e+09] m, and > wall_x1_min"),
])
def test_sim_init_refuses_a_bad_parameter(built, case, name, rule):
    """sim_init returns GAC_ERR_BAD_PARAMETER and leaves sim unchanged; check_parameters gives the same code and
    the index, whose row of the model's parameter table names the parameter and its rule."""
    result = drive(built, case)
    assert int(result["code"]) == code_of(built, "ERR_BAD_PARAMETER")
    assert result["same"] == "1"
    assert (result["name"], result["msg"]) == (name, rule)


@pytest.mark.parametrize("case", ["init_null_opt", "init_null_p"])
def test_sim_init_null_opt_and_p_mean_the_defaults(built, case):
    """opt NULL: default_options; p NULL: default_parameters; the run is bitwise the explicit one."""
    result = drive(built, case)
    assert int(result["code"]) == 0
    assert result["same"] == "1"


@pytest.mark.parametrize("depth,contact_tol,expected", [
    # DOPRI5 at the default rtol 1e-8, atol 1e-10 with points up to about 2.7 m: the simultaneity window is
    # 100 (atol + rtol l) = 2.7e-6 m, so the loop reports a lost contact below -(contact_tol + 2.7e-6 m)
    (0.0, 1e-6, "OK"),                       # on the floor
    (-1e-3, 1e-6, "OK"),                     # above it
    (0.5e-6, 1e-6, "OK"),                    # below it within contact_tol: a resting contact the loop holds
    (3e-6, 1e-6, "OK"),                      # within contact_tol + the window: a landing gap the loop can leave
    (1e-5, 1e-6, "ERR_START_OUTSIDE"),
    (1e-3, 1e-6, "ERR_START_OUTSIDE"),
    (1e-13, 0.0, "OK"),
    (1e-4, 0.0, "ERR_START_OUTSIDE"),
])
def test_sim_init_refuses_a_point_beyond_its_wall(built, depth, contact_tol, expected):
    result = drive(built, "floor", repr(depth), repr(contact_tol))
    code = 0 if expected == "OK" else code_of(built, expected)
    assert int(result["code"]) == code, result["msg"]
    if expected == "ERR_START_OUTSIDE":
        assert "beyond its wall" in result["msg"] and "contact_tol" in result["msg"]
        assert result["msg"] != drive(built, "adv_t_end_inf")["msg"]      # not the bad-option message


def test_start_outside_is_a_new_code(built):
    codes = [int(getattr(built[1].lib, name)) for name in return_codes()]
    assert len(codes) == len(set(codes)) == len(return_codes())
    assert code_of(built, "ERR_START_OUTSIDE") < 0 and code_of(built, "ERR_NULL_ARGUMENT") < 0


def test_sim_init_error_leaves_the_sim_unchanged(built):
    result = drive(built, "init_error_leaves_sim")
    assert int(result["code"]) == code_of(built, "ERR_START_OUTSIDE")
    assert result["same"] == "1"


def test_copies_are_bound_to_their_own_storage(built):
    result = drive(built, "copy")
    assert int(result["code"]) == 0 and result["same"] == "1"


def test_header_sizes_are_the_library_formulas(built):
    """NAME_<size> (gac.h's storage macros over the model's counts) equals what the library's functions compute for
    the descriptor."""
    model = built[1]
    lib, ffi = model.lib, model.ffi
    descriptor = ffi.addressof(lib.paper_case1_model)            # the const descriptor itself
    assert lib.gac_model_check(descriptor) == lib.GAC_OK
    assert descriptor.nq == lib.PAPER_CASE1_NQ == model.nq and descriptor.ncontact == lib.PAPER_CASE1_NCONTACT
    for suffix, formula in (("IMPACT_NWORK", lib.gac_impact_nwork), ("SIM_NDOUBLE", lib.gac_sim_ndouble),
                            ("SIM_NINT", lib.gac_sim_nint), ("RECORD_NDOUBLE", lib.gac_record_ndouble),
                            ("RECORD_NINT", lib.gac_record_nint)):
        assert formula(descriptor) == getattr(lib, f"PAPER_CASE1_{suffix}") == model.size(suffix), suffix


def test_sensitivities_through_the_per_model_wrappers_match_pythons(built):
    """NAME_sens_attach / NAME_sens_state with caller-owned storage of NAME_SENS_NDOUBLE(k) doubles: a run of
    paper-case1 through its impacts carries d x / d qd0[X1] and d x / d g as the Python front end's run does (the
    same library; the standalone build's flags may change the last bits)."""
    _, model = built
    result = drive(built, "sens")
    assert result["code"] == "0"
    assert int(result["status"]) == 0 and int(result["impacts"]) > 0
    S = np.array([float(v) for v in result["S"].split(",")]).reshape(2, -1).T
    r = simulate(model, 0.6, sensitivities=["qd0[X1]", "g"])
    assert r.sensitivities.valid and r.sensitivities.n_impacts == int(result["impacts"])
    assert np.allclose(S, r.sensitivities.matrix, rtol=1e-9, atol=1e-9 * np.abs(r.sensitivities.matrix).max())


def test_sim_state_and_default_options_ignore_null(built):
    result = drive(built, "state_null")
    assert int(result["code"]) == 0 and result["same"] == "1"


@pytest.mark.parametrize("case,expected", [
    ("adv_ok", "SIM_IMPACT"),
    ("adv_no_samples_null", "SIM_IMPACT"),  # n_eval = 0: t_eval, i_eval, x_eval may be NULL
    ("adv_null_sim", "ERR_NULL_ARGUMENT"),
    ("adv_null_record", "ERR_NULL_ARGUMENT"),
    ("adv_null_t_eval", "ERR_NULL_ARGUMENT"),
    ("adv_null_x_eval", "ERR_NULL_ARGUMENT"),
    ("adv_null_i_eval", "ERR_NULL_ARGUMENT"),
    ("adv_n_eval_negative", "ERR_BAD_OPTION"),
    ("adv_i_eval_negative", "ERR_BAD_OPTION"),
    ("adv_i_eval_past_n_eval", "ERR_BAD_OPTION"),
    ("adv_t_end_inf", "ERR_BAD_OPTION"),
    ("adv_t_end_nan", "ERR_BAD_OPTION"),
    ("adv_t_end_before_t", "ERR_BAD_OPTION"),
])
def test_sim_advance_refuses_bad_arguments(built, case, expected):
    result = drive(built, case)
    assert int(result["code"]) == code_of(built, expected), result["msg"]
    if expected.startswith("ERR_"):
        assert result["same"] == "1"                   # the refused call left the sim as it was
    if expected == "ERR_BAD_OPTION":
        assert "t_end finite" in result["msg"] and "n_eval >= 0" in result["msg"]
    if expected == "ERR_NULL_ARGUMENT":
        assert "NULL" in result["msg"] and "record" in result["msg"]


def example(built, *args):
    return subprocess.run([str(built[0] / "example"), *args], capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_example_help(built, flag):
    result = example(built, flag)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("usage: ") and "# paper_case1" not in result.stdout     # nothing simulated
    for text in ("t_end", "tol_or_dt", "dopri5", "dop853", "rk4", "--time N", "rtol 1e-8", "atol 1e-10", "--exact",
                 "--rtol R", "--event-samples K", "--contact-tol C", "--rest-height H", "--zeno-impacts K",
                 "--impact-law L", "newton-coulomb"):
        assert text in result.stdout


@pytest.mark.parametrize("args,named", [
    (["abc"], "t_end"),
    (["-1"], "t_end"),
    (["inf"], "t_end"),
    (["nan"], "t_end"),
    (["1.5x"], "t_end"),
    (["1", "euler"], "method"),
    (["1", "dopri5", "abc"], "tol_or_dt"),
    (["1", "dopri5", "0"], "tol_or_dt"),
    (["1", "dop853", "2"], "tol_or_dt"),
    (["1", "rk4", "-1e-3"], "tol_or_dt"),
    (["1", "dopri5", "1e-8", "extra"], "unexpected argument"),
    (["--frobnicate"], "unknown option"),
    (["1", "--time"], "--time"),
    (["1", "--time", "0"], "--time"),
    (["1", "--time", "two"], "--time"),
    (["1", "--rtol", "1e-15"], "--rtol"),
    (["1", "--atol", "0"], "--atol"),
    (["1", "rk4", "--dt", "0"], "--dt"),
    (["1", "--h-max", "inf"], "--h-max"),
    (["1", "--event-samples", "0"], "--event-samples"),
    (["1", "--event-tol", "nan"], "--event-tol"),
    (["1", "--contact-tol", "-1e-6"], "--contact-tol"),
    (["1", "--rest-height", "-2"], "--rest-height"),
    (["1", "--zeno-impacts", "1.5"], "--zeno-impacts"),
    (["1", "--max-steps", "-1"], "--max-steps"),
    (["1", "--impact-law", "coulomb"], "--impact-law"),
    (["1", "--impact-law"], "--impact-law"),
])
def test_example_refuses_bad_arguments(built, args, named):
    result = example(built, *args)
    assert result.returncode == 2, (result.stdout, result.stderr)
    assert result.stdout == ""                                           # nothing simulated
    first, usage = result.stderr.splitlines()[:2]
    shown = "(nothing)" if args in (["1", "--time"], ["1", "--impact-law"]) else args[-1]   # the value refused
    assert f": {named}" in first and f": got '{shown}', allowed " in first
    assert usage.startswith("usage: ")


def test_example_defaults_match_the_python_runtime(built, compiled):
    """No tolerance given: the library defaults (rtol 1e-8, atol 1e-10), as runtime.simulate's."""
    result = example(built, "1.5")
    assert result.returncode == 0, result.stderr
    c_times = [float(line.split()[1]) for line in result.stdout.splitlines() if re.match(r"^\s*\d+ \d", line)]
    python = simulate(compiled(load_scene("paper-case1"), specialise=True), 1.5, t_eval=[])
    assert len(c_times) == len(python.impacts) == 7
    assert max(abs(a - b.t) for a, b in zip(c_times, python.impacts)) < 1e-12


def test_example_keeps_its_positional_form_and_timing_option(built):
    result = example(built, "0.3", "dopri5", "1e-10", "--time", "2")
    assert result.returncode == 0, result.stderr
    assert "(2 runs)" in result.stdout and "# impacts 1," in result.stdout
    rk4 = example(built, "0.3", "rk4", "1e-4")
    assert rk4.returncode == 0 and "# impacts 1," in rk4.stdout
