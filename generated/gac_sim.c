/*
 * gac_sim.c -- the hybrid loop: flight integrated by RK4, DOPRI5 or DOP853 with dense output up to the next
 * event (a wall crossing located on the interpolant, or the release of a resting contact), the impact law
 * applied there (gac_impact.c), resting (persistent) contact held as bilateral constraints, and the floor
 * on the base chart's measure.  Sizes come from the model; arrays live in the caller's dwork / iwork.
 */
#include "gac_internal.h"

#include <math.h>
#include <string.h>

#define GAC_V_FLOOR 1e-12   /* m/s: a contact at its wall approaching slower than this, or than 1e-10 of
                               the fastest contact's normal speed (gac_v_round), is at rest: round-off */

/* Dormand-Prince 8(5,3) tableau with its 7th-order dense output (Hairer, Norsett & Wanner,
 * Solving ODEs I, 2nd ed., and the published dop853 coefficients).  Stages 13-15 serve the dense output. */
static const double gac_dop853_c[16] = {0.0, 0.05260015195876773, 0.0789002279381516, 0.1183503419072274, 0.2816496580927726, 0.3333333333333333, 0.25, 0.3076923076923077, 0.6512820512820513, 0.6, 0.8571428571428571, 1.0, 1.0, 0.1, 0.2, 0.7777777777777778};
static const double gac_dop853_a[16][16] = {
    {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {5.26001519587677318785587544488e-2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {2.95875854768068491816892993775e-2, 0.0, 8.87627564304205475450678981324e-2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {2.41365134159266685502369798665e-1, 0.0, -8.84549479328286085344864962717e-1, 9.24834003261792003115737966543e-1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {3.7037037037037037037037037037e-2, 0.0, 0.0, 1.70828608729473871279604482173e-1, 1.25467687566822425016691814123e-1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {3.7109375e-2, 0.0, 0.0, 1.70252211019544039314978060272e-1, 6.02165389804559606850219397283e-2, -1.7578125e-2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {3.70920001185047927108779319836e-2, 0.0, 0.0, 1.70383925712239993810214054705e-1, 1.07262030446373284651809199168e-1, -1.53194377486244017527936158236e-2, 8.27378916381402288758473766002e-3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {6.24110958716075717114429577812e-1, 0.0, 0.0, -3.36089262944694129406857109825, -8.68219346841726006818189891453e-1, 2.75920996994467083049415600797e1, 2.01540675504778934086186788979e1, -4.34898841810699588477366255144e1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {4.77662536438264365890433908527e-1, 0.0, 0.0, -2.48811461997166764192642586468, -5.90290826836842996371446475743e-1, 2.12300514481811942347288949897e1, 1.52792336328824235832596922938e1, -3.32882109689848629194453265587e1, -2.03312017085086261358222928593e-2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {-9.3714243008598732571704021658e-1, 0.0, 0.0, 5.18637242884406370830023853209, 1.09143734899672957818500254654, -8.14978701074692612513997267357, -1.85200656599969598641566180701e1, 2.27394870993505042818970056734e1, 2.49360555267965238987089396762, -3.0467644718982195003823669022, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0},
    {2.27331014751653820792359768449, 0.0, 0.0, -1.05344954667372501984066689879e1, -2.00087205822486249909675718444, -1.79589318631187989172765950534e1, 2.79488845294199600508499808837e1, -2.85899827713502369474065508674, -8.87285693353062954433549289258, 1.23605671757943030647266201528e1, 6.43392746015763530355970484046e-1, 0.0, 0.0, 0.0, 0.0, 0.0},
    {5.42937341165687622380535766363e-2, 0.0, 0.0, 0.0, 0.0, 4.45031289275240888144113950566, 1.89151789931450038304281599044, -5.8012039600105847814672114227, 3.1116436695781989440891606237e-1, -1.52160949662516078556178806805e-1, 2.01365400804030348374776537501e-1, 4.47106157277725905176885569043e-2, 0.0, 0.0, 0.0, 0.0},
    {5.61675022830479523392909219681e-2, 0.0, 0.0, 0.0, 0.0, 0.0, 2.53500210216624811088794765333e-1, -2.46239037470802489917441475441e-1, -1.24191423263816360469010140626e-1, 1.5329179827876569731206322685e-1, 8.20105229563468988491666602057e-3, 7.56789766054569976138603589584e-3, -8.298e-3, 0.0, 0.0, 0.0},
    {3.18346481635021405060768473261e-2, 0.0, 0.0, 0.0, 0.0, 2.83009096723667755288322961402e-2, 5.35419883074385676223797384372e-2, -5.49237485713909884646569340306e-2, 0.0, 0.0, -1.08347328697249322858509316994e-4, 3.82571090835658412954920192323e-4, -3.40465008687404560802977114492e-4, 1.41312443674632500278074618366e-1, 0.0, 0.0},
    {-4.28896301583791923408573538692e-1, 0.0, 0.0, 0.0, 0.0, -4.69762141536116384314449447206, 7.68342119606259904184240953878, 4.06898981839711007970213554331, 3.56727187455281109270669543021e-1, 0.0, 0.0, 0.0, -1.39902416515901462129418009734e-3, 2.9475147891527723389556272149, -9.15095847217987001081870187138, 0.0},
};
static const double gac_dop853_e5[13] = {0.1312004499419488073250102996e-1, 0.0, 0.0, 0.0, 0.0, -0.1225156446376204440720569753e1, -0.4957589496572501915214079952, 0.1664377182454986536961530415e1, -0.3503288487499736816886487290, 0.3341791187130174790297318841, 0.8192320648511571246570742613e-1, -0.2235530786388629525884427845e-1, 0.0};
/* e3 = b - bhh (bhh: the 3rd-order embedded weights, nonzero at stages 0, 8, 11) */
static const double gac_dop853_bhh[12] = {0.244094488188976377952755905512, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.733846688281611857341361741547, 0.0, 0.0, 0.220588235294117647058823529412e-1};
static const double gac_dop853_d[4][16] = {
    {-0.84289382761090128651353491142e1, 0.0, 0.0, 0.0, 0.0, 0.56671495351937776962531783590, -0.30689499459498916912797304727e1, 0.23846676565120698287728149680e1, 0.21170345824450282767155149946e1, -0.87139158377797299206789907490, 0.22404374302607882758541771650e1, 0.63157877876946881815570249290, -0.88990336451333310820698117400e-1, 0.18148505520854727256656404962e2, -0.91946323924783554000451984436e1, -0.44360363875948939664310572000e1},
    {0.10427508642579134603413151009e2, 0.0, 0.0, 0.0, 0.0, 0.24228349177525818288430175319e3, 0.16520045171727028198505394887e3, -0.37454675472269020279518312152e3, -0.22113666853125306036270938578e2, 0.77334326684722638389603898808e1, -0.30674084731089398182061213626e2, -0.93321305264302278729567221706e1, 0.15697238121770843886131091075e2, -0.31139403219565177677282850411e2, -0.93529243588444783865713862664e1, 0.35816841486394083752465898540e2},
    {0.19985053242002433820987653617e2, 0.0, 0.0, 0.0, 0.0, -0.38703730874935176555105901742e3, -0.18917813819516756882830838328e3, 0.52780815920542364900561016686e3, -0.11573902539959630126141871134e2, 0.68812326946963000169666922661e1, -0.10006050966910838403183860980e1, 0.77771377980534432092869265740, -0.27782057523535084065932004339e1, -0.60196695231264120758267380846e2, 0.84320405506677161018159903784e2, 0.11992291136182789328035130030e2},
    {-0.25693933462703749003312586129e2, 0.0, 0.0, 0.0, 0.0, -0.15418974869023643374053993627e3, -0.23152937917604549567536039109e3, 0.35763911791061412378285349910e3, 0.93405324183624310003907691704e2, -0.37458323136451633156875139351e2, 0.10409964950896230045147246184e3, 0.29840293426660503123344363579e2, -0.43533456590011143754432175058e2, 0.96324553959188282948394950600e2, -0.39177261675615439165231486172e2, -0.14972683625798562581422125276e3},
};

void gac_default_options(gac_options *opt)
{
    if (opt == 0) return;
    opt->method = GAC_METHOD_DOPRI5;
    opt->dt = 0.0;
    opt->rtol = 1e-8;
    opt->atol = 1e-10;
    opt->h_max = 0.0;
    opt->event_samples = 4;
    opt->event_tol = 1e-13;
    opt->contact_tol = 1e-6;
    opt->max_steps = 10000000L;
    opt->rest_height = -1.0;
    opt->zeno_impacts = 20;
}

/* dst[0..n-1] = src[0..n-1] (distinct arrays). */
static void gac_copy(double *dst, const double *src, int n)
{
    if (n > 0) memcpy(dst, src, (size_t)n * sizeof *dst);
}

static int gac_finite(const double *x, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (!(x[i] - x[i] == 0.0)) return 0;
    }
    return 1;
}

/* The inputs at time t and state x: the held ones, or the controller's (into s->u_eval, starting from the
 * held ones).  A non-finite controller output is kept in s->fail (GAC_ERR_BAD_INPUT). */
static const double *gac_input(gac_sim *s, double t, const double *x)
{
    const gac_model *md = s->model;
    if (s->controller == 0 || md->nu == 0) return s->u;
    gac_copy(s->u_eval, s->u, md->nu);
    s->controller(t, x, x + md->nq, s->u_eval, s->controller_data);
    if (!gac_finite(s->u_eval, md->nu) && s->fail == 0) s->fail = GAC_ERR_BAD_INPUT;
    return s->u_eval;
}

/* The flight right-hand side: free, or with the persistent contacts held (an error is kept in s->fail;
 * in a trial stage of an adaptive step it only rejects the step). */
static void gac_f(gac_sim *s, double t, const double *x, double *f)
{
    const gac_model *md = s->model;
    const double *u = gac_input(s, t, x);
    s->n_rhs++;
    if (s->nactive == 0) {
        md->rhs(t, x, u, s->p, f);
    } else {
        double lambda[md->nq];
        int i, code;
        for (i = 0; i < md->nq; ++i) f[i] = x[md->nq + i];
        code = gac_constrained_dynamics(md, x, x + md->nq, u, s->p, s->nactive, s->active, f + md->nq, lambda,
                                        s->work);
        if (code != GAC_OK && s->fail == 0) s->fail = code;
    }
}

/* Event value of every contact at time t and state x: its gap, or for a persistent contact its force lambda.
 * An event is a value falling from > 0 to <= 0: a wall crossing, or a persistent contact that would pull. */
static void gac_events(gac_sim *s, double t, const double *x, double *ev)
{
    const gac_model *md = s->model;
    md->contact_gaps(x, s->p, ev);
    if (s->nactive > 0) {
        double qdd[md->nq], lambda[md->nq];
        const double *u = gac_input(s, t, x);
        int a, code;
        for (a = 0; a < md->nq; ++a) lambda[a] = 0.0;
        code = gac_constrained_dynamics(md, x, x + md->nq, u, s->p, s->nactive, s->active, qdd, lambda, s->work);
        if (code != GAC_OK && s->fail == 0) s->fail = code;
        for (a = 0; a < s->nactive; ++a) ev[s->active[a]] = lambda[a];
    }
}

static int gac_rest_at_start(gac_sim *s);

void gac_sim_bind(gac_sim *s, const gac_model *md, double *dwork, int *iwork)
{
    const int nx = md->nx, nc1 = GAC_AT_LEAST_1(md->ncontact);
    double *d = dwork;
    int j;
    s->model = md;
    s->x = d;             d += nx;             /* dwork: x | p | u | u_eval | f | k[0..15] | x1 | xs | cont[0..7] */
    s->p = d;             d += md->nparam;
    s->u = d;             d += md->nu;
    s->u_eval = d;        d += md->nu;
    s->f = d;             d += nx;
    for (j = 0; j < 16; ++j) {
        s->k[j] = d;
        d += nx;
    }
    s->x1 = d;            d += nx;
    s->xs = d;            d += nx;
    for (j = 0; j < 8; ++j) {
        s->cont[j] = d;
        d += nx;
    }
    s->ev = d;            d += nc1;            /* | ev | es | eprev | vn | t_last | dt_last | gap_held */
    s->es = d;            d += nc1;
    s->eprev = d;         d += nc1;
    s->vn = d;            d += nc1;
    s->t_last = d;        d += nc1;
    s->dt_last = d;       d += nc1;
    s->gap_held = d;      d += nc1;
    s->work = d;          d += gac_impact_nwork(md);   /* | work | sub */
    s->sub = d;
    s->active = iwork;                         /* iwork: active | is_active | n_shrink */
    s->is_active = iwork + md->nq;
    s->n_shrink = iwork + md->nq + nc1;
}

/* gac_sim_init once its pointers and the model are checked: the options, the state and the start inside
 * the walls checked before anything is written. */
static int gac_sim_start(gac_sim *s, const gac_model *md, double *dwork, int *iwork, double t0,
                         const double *q, const double *qd, const double *p, const gac_options *opt)
{
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    double x[md->nx], pv[GAC_AT_LEAST_1(md->nparam)];
    int i;
    if (opt->method != GAC_METHOD_RK4 && opt->method != GAC_METHOD_DOPRI5
        && opt->method != GAC_METHOD_DOP853) return GAC_ERR_BAD_OPTION;
    if (opt->method == GAC_METHOD_RK4 && !(opt->dt > 0.0 && opt->dt < 1e300)) return GAC_ERR_BAD_OPTION;
    if (opt->method != GAC_METHOD_RK4 && !(opt->rtol > 0.0 && opt->atol > 0.0 && opt->dt >= 0.0))
        return GAC_ERR_BAD_OPTION;
    if (opt->event_samples < 1 || !(opt->event_tol > 0.0) || !(opt->contact_tol >= 0.0) || !(opt->h_max >= 0.0)
        || opt->max_steps < 0 || !(opt->rest_height < 1e300) || opt->zeno_impacts < 0)
        return GAC_ERR_BAD_OPTION;
    for (i = 0; i < md->nparam; ++i) pv[i] = p == 0 ? md->default_parameters[i] : p[i];   /* NULL: the defaults */
    for (i = 0; i < md->nq; ++i) {
        x[i] = q[i];
        x[md->nq + i] = qd[i];
    }
    if (!gac_finite(x, md->nx) || !gac_finite(&t0, 1)) return GAC_ERR_BAD_OPTION;
    {
        /* every point on the right side of its wall, to the depth at which the loop itself reports a lost
         * contact (GAC_ERR_LOST_CONTACT): contact_tol plus the simultaneity window (contact_tol, or 100 times
         * an adaptive method's position tolerance atol + rtol l if larger), plus round-off 1e-12 max(1 m, l),
         * l the largest |point coordinate|.  So the states the loop leaves (a resting contact held at its
         * landing gap) restart, and a point really outside is refused. */
        double gaps[nc1], r[3 * md->npoint], size = 1.0, window, depth;
        md->contact_points(x, pv, r);
        for (i = 0; i < 3 * md->npoint; ++i) {
            if (fabs(r[i]) > size) size = fabs(r[i]);
        }
        md->contact_gaps(x, pv, gaps);
        window = opt->method == GAC_METHOD_RK4 ? 0.0 : 100.0 * (opt->atol + opt->rtol * size);
        if (window < opt->contact_tol) window = opt->contact_tol;
        depth = opt->contact_tol + window + 1e-12 * size;
        for (i = 0; i < md->ncontact; ++i) {
            if (gaps[i] < -depth) return GAC_ERR_START_OUTSIDE;
        }
    }
    gac_sim_bind(s, md, dwork, iwork);
    s->opt = *opt;
    for (i = 0; i < md->nparam; ++i) s->p[i] = pv[i];
    for (i = 0; i < md->nu; ++i) s->u[i] = s->u_eval[i] = 0.0;
    s->controller = 0;
    s->controller_data = 0;
    s->input_changed = 0;
    s->work_input = s->work_damping = s->work_friction = 0.0;
    s->n_slow_sliding = 0;
    s->t_slow_sliding = 0.0;
    for (i = 0; i < md->nx; ++i) s->x[i] = x[i];
    s->t = t0;
    s->h = opt->dt;                               /* RK4 step, or the first adaptive step (0: automatic) */
    s->f_valid = 0;
    s->n_steps = s->n_rejected = s->n_rhs = s->n_impacts = 0;
    s->nactive = 0;
    s->n_activations = s->n_releases = 0;
    s->pending = s->fail = s->fail_seen = 0;
    s->vn_valid = 0;
    s->err_index = s->n_unstable = 0;
    s->t0_step = t0;
    s->h_step = 0.0;
    s->rest_height = opt->rest_height < 0.0 ? 10.0 * opt->contact_tol : opt->rest_height;
    {
        double r[3 * md->npoint], length = 0.0;   /* the chain's length: sum of |O_k+1 - O_k| */
        md->contact_points(s->x, s->p, r);
        for (i = 3; i < 3 * md->npoint; i += 3) {
            length += sqrt((r[i] - r[i - 3]) * (r[i] - r[i - 3]) + (r[i + 1] - r[i - 2]) * (r[i + 1] - r[i - 2])
                           + (r[i + 2] - r[i - 1]) * (r[i + 2] - r[i - 1]));
        }
        s->lever = length > 1.0 ? length : 1.0;
    }
    for (i = 0; i < nc1; ++i) {
        s->is_active[i] = 0;
        s->n_shrink[i] = 0;
        s->t_last[i] = t0;
        s->dt_last[i] = -2.0;                     /* -2: no impact of this contact yet, -1: one */
        s->gap_held[i] = 0.0;
    }
    if (s->rest_height > 0.0) {
        int code = gac_rest_at_start(s);
        if (code < 0) return code;
    }
    gac_events(s, s->t, s->x, s->ev);
    return s->fail < 0 ? s->fail : GAC_OK;
}

int gac_sim_init(gac_sim *s, const gac_model *m, double *dwork, int *iwork, double t0, const double *q,
                 const double *qd, const double *p, const gac_options *opt)
{
    gac_options defaults;
    int code;
    if (s == 0 || m == 0 || dwork == 0 || iwork == 0 || q == 0 || qd == 0) return GAC_ERR_NULL_ARGUMENT;
    code = gac_model_check(m);
    if (code != GAC_OK) return code;
    if (opt == 0) {                                /* NULL: the default options */
        gac_default_options(&defaults);
        opt = &defaults;
    }
    return gac_sim_start(s, m, dwork, iwork, t0, q, qd, p, opt);
}

void gac_record_bind(gac_impact_record *r, const gac_model *m, double *dwork, int *iwork)
{
    const int nq = m->nq;
    r->impulse = dwork;                        /* dwork: impulse | q | qd_before | qd_after */
    r->q = dwork + nq;
    r->qd_before = dwork + 2 * nq;
    r->qd_after = dwork + 3 * nq;
    r->contact = iwork;                        /* iwork: contact | activated | released */
    r->activated = iwork + nq;
    r->released = iwork + 2 * nq;
}

void gac_sim_state(const gac_sim *s, double *t, double *q, double *qd)
{
    int i;
    if (s == 0) return;
    if (t != 0) *t = s->t;
    for (i = 0; i < s->model->nq; ++i) {
        if (q != 0) q[i] = s->x[i];
        if (qd != 0) qd[i] = s->x[s->model->nq + i];
    }
}

/* Weighted RMS norm of d with scale atol + rtol max(|y0|, |y1|). */
static double gac_norm(gac_sim *s, const double *d, const double *y0, const double *y1)
{
    const gac_model *md = s->model;
    int i;
    double sum = 0.0, largest = -1.0;
    for (i = 0; i < md->nx; ++i) {
        double a = fabs(y0[i]), b = fabs(y1[i]);
        double scale = s->opt.atol + s->opt.rtol * (a > b ? a : b);
        double r = (d[i] / scale) * (d[i] / scale);
        sum += r;
        if (r > largest) {
            largest = r;
            s->err_index = i;
        }
    }
    return sqrt(sum / md->nx);
}

/* Starting step for DOPRI5 (Hairer, Norsett & Wanner, Solving ODEs I, Sect. II.4). */
static double gac_initial_step(gac_sim *s, double t_end)
{
    const gac_model *md = s->model;
    double d0, d1, d2, h0, h1, h;
    int i;
    d0 = gac_norm(s, s->x, s->x, s->x);
    d1 = gac_norm(s, s->f, s->x, s->x);
    h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    if (h0 > t_end - s->t) h0 = t_end - s->t;
    for (i = 0; i < md->nx; ++i) s->xs[i] = s->x[i] + h0 * s->f[i];
    gac_f(s, s->t + h0, s->xs, s->k[1]);
    for (i = 0; i < md->nx; ++i) s->k[1][i] -= s->f[i];
    d2 = gac_norm(s, s->k[1], s->x, s->x) / h0;
    h1 = (d1 > d2 ? d1 : d2) <= 1e-15 ? (h0 * 1e-3 > 1e-6 ? h0 * 1e-3 : 1e-6)
         : pow(0.01 / (d1 > d2 ? d1 : d2), s->opt.method == GAC_METHOD_DOP853 ? 0.125 : 0.2);
    h = 100.0 * h0 < h1 ? 100.0 * h0 : h1;
    return h;
}

/* Stage sums of the Runge-Kutta steps over the nx = 2 nq state entries, entry by entry as written out:
 * y = x + ha k, y = x + h (a1 k1 + ... + am km) (m = 2..5), y = h (a1 k1 + ... + a6 k6).  Separate functions
 * with restrict arguments and an even length let the compiler vectorise the loops; each entry's arithmetic is
 * the expression shown. */
static void gac_stage1(int nq, double *GAC_RESTRICT y, const double *GAC_RESTRICT x, double ha,
                       const double *GAC_RESTRICT k)
{
    const int nx = 2 * nq;
    int i;
    for (i = 0; i < nx; ++i) y[i] = x[i] + ha * k[i];
}

static void gac_stage2(int nq, double *GAC_RESTRICT y, const double *GAC_RESTRICT x, double h, double a1,
                       const double *GAC_RESTRICT k1, double a2, const double *GAC_RESTRICT k2)
{
    const int nx = 2 * nq;
    int i;
    for (i = 0; i < nx; ++i) y[i] = x[i] + h * (a1 * k1[i] + a2 * k2[i]);
}

static void gac_stage3(int nq, double *GAC_RESTRICT y, const double *GAC_RESTRICT x, double h, double a1,
                       const double *GAC_RESTRICT k1, double a2, const double *GAC_RESTRICT k2, double a3,
                       const double *GAC_RESTRICT k3)
{
    const int nx = 2 * nq;
    int i;
    for (i = 0; i < nx; ++i) y[i] = x[i] + h * (a1 * k1[i] + a2 * k2[i] + a3 * k3[i]);
}

static void gac_stage4(int nq, double *GAC_RESTRICT y, const double *GAC_RESTRICT x, double h, double a1,
                       const double *GAC_RESTRICT k1, double a2, const double *GAC_RESTRICT k2, double a3,
                       const double *GAC_RESTRICT k3, double a4, const double *GAC_RESTRICT k4)
{
    const int nx = 2 * nq;
    int i;
    for (i = 0; i < nx; ++i) y[i] = x[i] + h * (a1 * k1[i] + a2 * k2[i] + a3 * k3[i] + a4 * k4[i]);
}

static void gac_stage5(int nq, double *GAC_RESTRICT y, const double *GAC_RESTRICT x, double h, double a1,
                       const double *GAC_RESTRICT k1, double a2, const double *GAC_RESTRICT k2, double a3,
                       const double *GAC_RESTRICT k3, double a4, const double *GAC_RESTRICT k4, double a5,
                       const double *GAC_RESTRICT k5)
{
    const int nx = 2 * nq;
    int i;
    for (i = 0; i < nx; ++i) y[i] = x[i] + h * (a1 * k1[i] + a2 * k2[i] + a3 * k3[i] + a4 * k4[i] + a5 * k5[i]);
}

static void gac_error6(int nq, double *GAC_RESTRICT y, double h, double a1, const double *GAC_RESTRICT k1,
                       double a2, const double *GAC_RESTRICT k2, double a3, const double *GAC_RESTRICT k3,
                       double a4, const double *GAC_RESTRICT k4, double a5, const double *GAC_RESTRICT k5,
                       double a6, const double *GAC_RESTRICT k6)
{
    const int nx = 2 * nq;
    int i;
    for (i = 0; i < nx; ++i) y[i] = h * (a1 * k1[i] + a2 * k2[i] + a3 * k3[i] + a4 * k4[i] + a5 * k5[i] + a6 * k6[i]);
}

/* One RK4 step of size h from (t, x, f): x1, its derivative k[4], and the Hermite dense output.  Returns
 * h rho, rho = |k4 - k3| / |Y4 - Y3| the rate of the chain's fastest mode seen between the last two stages
 * (Y3 = x + h/2 k2, Y4 = x + h k3; Hairer & Wanner's stiffness detection): RK4 is stable for h rho below
 * about 2.8. */
static double gac_rk4_step(gac_sim *s, double h)
{
    const gac_model *md = s->model;
    int i;
    const int nx = md->nx;
    double *k2 = s->k[1], *k3 = s->k[2], *k4 = s->k[3], dk = 0.0, dy = 0.0;
    gac_stage1(md->nq, s->xs, s->x, 0.5 * h, s->f);
    gac_f(s, s->t + 0.5 * h, s->xs, k2);
    gac_stage1(md->nq, s->xs, s->x, 0.5 * h, k2);
    gac_f(s, s->t + 0.5 * h, s->xs, k3);
    gac_stage1(md->nq, s->xs, s->x, h, k3);
    gac_f(s, s->t + h, s->xs, k4);
    for (i = 0; i < nx; ++i) {
        const double d = h * k3[i] - 0.5 * h * k2[i];
        dk += (k4[i] - k3[i]) * (k4[i] - k3[i]);
        dy += d * d;
        s->x1[i] = s->x[i] + h / 6.0 * (s->f[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
    gac_f(s, s->t + h, s->x1, s->k[4]);        /* derivative at the end: Hermite and next step */
    return dy > 0.0 ? h * sqrt(dk / dy) : 0.0;
}

/* One Dormand-Prince 5(4) step of size h; returns the error norm; x1 and k[6] = f(t + h, x1). */
static double gac_dopri5_step(gac_sim *s, double h)
{
    const gac_model *md = s->model;
    const double
        a21 = 1.0 / 5.0,
        a31 = 3.0 / 40.0, a32 = 9.0 / 40.0,
        a41 = 44.0 / 45.0, a42 = -56.0 / 15.0, a43 = 32.0 / 9.0,
        a51 = 19372.0 / 6561.0, a52 = -25360.0 / 2187.0, a53 = 64448.0 / 6561.0, a54 = -212.0 / 729.0,
        a61 = 9017.0 / 3168.0, a62 = -355.0 / 33.0, a63 = 46732.0 / 5247.0, a64 = 49.0 / 176.0,
        a65 = -5103.0 / 18656.0,
        a71 = 35.0 / 384.0, a73 = 500.0 / 1113.0, a74 = 125.0 / 192.0, a75 = -2187.0 / 6784.0,
        a76 = 11.0 / 84.0,
        e1 = 71.0 / 57600.0, e3 = -71.0 / 16695.0, e4 = 71.0 / 1920.0, e5 = -17253.0 / 339200.0,
        e6 = 22.0 / 525.0, e7 = -1.0 / 40.0;
    const int nq = md->nq;
    double *k1 = s->f, *k2 = s->k[1], *k3 = s->k[2], *k4 = s->k[3], *k5 = s->k[4], *k6 = s->k[5], *k7 = s->k[6];
    const double t = s->t;
    gac_stage1(nq, s->xs, s->x, h * a21, k1);
    gac_f(s, t + h / 5.0, s->xs, k2);
    gac_stage2(nq, s->xs, s->x, h, a31, k1, a32, k2);
    gac_f(s, t + 0.3 * h, s->xs, k3);
    gac_stage3(nq, s->xs, s->x, h, a41, k1, a42, k2, a43, k3);
    gac_f(s, t + 0.8 * h, s->xs, k4);
    gac_stage4(nq, s->xs, s->x, h, a51, k1, a52, k2, a53, k3, a54, k4);
    gac_f(s, t + h * 8.0 / 9.0, s->xs, k5);
    gac_stage5(nq, s->xs, s->x, h, a61, k1, a62, k2, a63, k3, a64, k4, a65, k5);
    gac_f(s, t + h, s->xs, k6);
    gac_stage5(nq, s->x1, s->x, h, a71, k1, a73, k3, a74, k4, a75, k5, a76, k6);
    gac_f(s, t + h, s->x1, k7);
    gac_error6(nq, s->xs, h, e1, k1, e3, k3, e4, k4, e5, k5, e6, k6, e7, k7);   /* the error estimate, in xs */
    return gac_norm(s, s->xs, s->x, s->x1);
}

/* DOP853 stages first..last-1: K[stage] = f(t + c[stage] h, x + h sum_j a[stage][j] K[j]). */
static void gac_dop853_stages(gac_sim *s, double h, double *const *K, int first, int last)
{
    const int nx = s->model->nx;
    int i, j, stage;
    for (stage = first; stage < last; ++stage) {
        const double *a = gac_dop853_a[stage];
        for (i = 0; i < nx; ++i) {
            double sum = 0.0;
            for (j = 0; j < stage; ++j) sum += a[j] * K[j][i];
            s->xs[i] = s->x[i] + h * sum;
        }
        gac_f(s, s->t + gac_dop853_c[stage] * h, s->xs, K[stage]);
    }
}

/* One Dormand-Prince 8(5,3) step of size h; returns the error norm (Hairer's combined 5th/3rd-order
 * estimate); x1 and k[12] = f(t + h, x1).  Stage i is k[i] (k[0] is s->f). */
static double gac_dop853_step(gac_sim *s, double h)
{
    const gac_model *md = s->model;
    const int nx = md->nx;
    double *K[13];
    double e5 = 0.0, e3 = 0.0, largest = -1.0;
    int i, j;
    K[0] = s->f;
    for (j = 1; j < 13; ++j) K[j] = s->k[j];
    gac_dop853_stages(s, h, K, 1, 12);
    for (i = 0; i < nx; ++i) {                     /* 8th-order solution: weights are row 12 of a */
        double sum = 0.0;
        for (j = 0; j < 12; ++j) sum += gac_dop853_a[12][j] * K[j][i];
        s->x1[i] = s->x[i] + h * sum;
    }
    gac_f(s, s->t + h, s->x1, K[12]);
    for (i = 0; i < nx; ++i) {
        double err5 = 0.0, err3 = 0.0, a = fabs(s->x[i]), b = fabs(s->x1[i]);
        double scale = s->opt.atol + s->opt.rtol * (a > b ? a : b);
        for (j = 0; j < 12; ++j) {
            err5 += gac_dop853_e5[j] * K[j][i];
            err3 += (gac_dop853_a[12][j] - gac_dop853_bhh[j]) * K[j][i];
        }
        e5 += (err5 / scale) * (err5 / scale);
        e3 += (err3 / scale) * (err3 / scale);
        if ((err5 / scale) * (err5 / scale) > largest) {
            largest = (err5 / scale) * (err5 / scale);
            s->err_index = i;
        }
    }
    if (e5 == 0.0 && e3 == 0.0) return 0.0;
    return fabs(h) * e5 / sqrt((e5 + 0.01 * e3) * nx);
}

/* The dense outputs on the nx = 2 nq state entries (separate functions for the reason given at gac_stage1):
 * cubic Hermite (RK4), Hairer's contd5 (DOPRI5) and contd8 (DOP853) evaluated at th = (t - t0) / h,
 * th1 = 1 - th, and the contd5 coefficients of a DOPRI5 step. */
static void gac_hermite(int nq, double *GAC_RESTRICT out, const double *GAC_RESTRICT c0,
                        const double *GAC_RESTRICT c1, const double *GAC_RESTRICT c2, const double *GAC_RESTRICT c3,
                        double h00, double h01, double h10, double h11)
{
    const int nx = 2 * nq;
    int i;
    for (i = 0; i < nx; ++i) out[i] = h00 * c0[i] + h01 * c1[i] + h10 * c2[i] + h11 * c3[i];
}

static void gac_contd5(int nq, double *GAC_RESTRICT out, const double *GAC_RESTRICT c0,
                       const double *GAC_RESTRICT c1, const double *GAC_RESTRICT c2, const double *GAC_RESTRICT c3,
                       const double *GAC_RESTRICT c4, double th, double th1)
{
    const int nx = 2 * nq;
    int i;
    for (i = 0; i < nx; ++i) out[i] = c0[i] + th * (c1[i] + th1 * (c2[i] + th * (c3[i] + th1 * c4[i])));
}

static void gac_contd8(int nq, double *GAC_RESTRICT out, double *const *cont, double th, double th1)
{
    const int nx = 2 * nq;
    const double *GAC_RESTRICT c0 = cont[0], *GAC_RESTRICT c1 = cont[1], *GAC_RESTRICT c2 = cont[2];
    const double *GAC_RESTRICT c3 = cont[3], *GAC_RESTRICT c4 = cont[4], *GAC_RESTRICT c5 = cont[5];
    const double *GAC_RESTRICT c6 = cont[6], *GAC_RESTRICT c7 = cont[7];
    int i;
    for (i = 0; i < nx; ++i) {
        double y = c6[i] * th;
        y = (y + c5[i]) * th1;
        y = (y + c4[i]) * th;
        y = (y + c3[i]) * th1;
        y = (y + c2[i]) * th;
        y = (y + c1[i]) * th1;
        y = (y + c0[i]) * th;
        out[i] = c7[i] + y;
    }
}

/* contd5 of a DOPRI5 step from x to x1 with stages f (k1), k2..k6 (k7 = k6 of the FSAL step: f(t + h, x1)). */
static void gac_prepare_contd5(int nq, double h, double *GAC_RESTRICT c0, double *GAC_RESTRICT c1,
                               double *GAC_RESTRICT c2, double *GAC_RESTRICT c3, double *GAC_RESTRICT c4,
                               const double *GAC_RESTRICT x, const double *GAC_RESTRICT x1,
                               const double *GAC_RESTRICT f, const double *GAC_RESTRICT k3,
                               const double *GAC_RESTRICT k4, const double *GAC_RESTRICT k5,
                               const double *GAC_RESTRICT k6, const double *GAC_RESTRICT k7)
{
    const double
        d1 = -12715105075.0 / 11282082432.0, d3 = 87487479700.0 / 32700410799.0,
        d4 = -10690763975.0 / 1880347072.0, d5 = 701980252875.0 / 199316789632.0,
        d6 = -1453857185.0 / 822651844.0, d7 = 69997945.0 / 29380423.0;
    const int nx = 2 * nq;
    int i;
    for (i = 0; i < nx; ++i) {
        double dy = x1[i] - x[i];
        double bspl = h * f[i] - dy;
        c0[i] = x[i];
        c1[i] = dy;
        c2[i] = bspl;
        c3[i] = dy - h * k7[i] - bspl;
        c4[i] = h * (d1 * f[i] + d3 * k3[i] + d4 * k4[i] + d5 * k5[i] + d6 * k6[i] + d7 * k7[i]);
    }
}

/* Dense output of the accepted step [t0_step, t0_step + h_step] (k[] as left by the step). */
static void gac_prepare_dense(gac_sim *s, double h)
{
    const gac_model *md = s->model;
    int i;
    const int nx = md->nx;
    s->t0_step = s->t;
    s->h_step = h;
    if (s->opt.method == GAC_METHOD_RK4) {       /* cubic Hermite: x0, x1, f0, f1 */
        for (i = 0; i < nx; ++i) {
            s->cont[0][i] = s->x[i];
            s->cont[1][i] = s->x1[i];
            s->cont[2][i] = h * s->f[i];
            s->cont[3][i] = h * s->k[4][i];
        }
    } else if (s->opt.method == GAC_METHOD_DOP853) {   /* three more stages, then contd8 */
        double *K[16];
        int j, r;
        K[0] = s->f;
        for (j = 1; j < 16; ++j) K[j] = s->k[j];
        gac_dop853_stages(s, h, K, 13, 16);
        for (i = 0; i < nx; ++i) {
            double dy = s->x1[i] - s->x[i];
            s->cont[7][i] = s->x[i];
            s->cont[0][i] = dy;
            s->cont[1][i] = h * K[0][i] - dy;
            s->cont[2][i] = 2.0 * dy - h * (K[12][i] + K[0][i]);
            for (r = 0; r < 4; ++r) {
                double sum = 0.0;
                for (j = 0; j < 16; ++j) sum += gac_dop853_d[r][j] * K[j][i];
                s->cont[3 + r][i] = h * sum;
            }
        }
    } else {                                           /* Hairer's contd5 coefficients */
        gac_prepare_contd5(md->nq, h, s->cont[0], s->cont[1], s->cont[2], s->cont[3], s->cont[4], s->x, s->x1,
                           s->f, s->k[2], s->k[3], s->k[4], s->k[5], s->k[6]);
    }
}

/* State at time t inside the current step, into out. */
static void gac_dense(gac_sim *s, double t, double *out)
{
    const int nq = s->model->nq;
    const double th = (t - s->t0_step) / s->h_step, th1 = 1.0 - th;
    if (s->opt.method == GAC_METHOD_RK4) {
        const double h00 = (1.0 + 2.0 * th) * th1 * th1, h01 = th * th * (3.0 - 2.0 * th);
        const double h10 = th * th1 * th1, h11 = -th * th * th1;
        gac_hermite(nq, out, s->cont[0], s->cont[1], s->cont[2], s->cont[3], h00, h01, h10, h11);
    } else if (s->opt.method == GAC_METHOD_DOP853) {
        gac_contd8(nq, out, s->cont, th, th1);
    } else {
        gac_contd5(nq, out, s->cont[0], s->cont[1], s->cont[2], s->cont[3], s->cont[4], th, th1);
    }
}

static void gac_normal_velocities(const gac_model *md, const double *x, const double *p, double *vn);

/* The normal speed below which an approach is round-off, given every contact's normal velocity vn:
 * GAC_V_FLOOR + 1e-10 max|vn| (the law's round-off floor on the chain's own speeds). */
static double gac_v_round(const gac_model *md, const double *vn)
{
    double scale = 0.0;
    int c;
    for (c = 0; c < md->ncontact; ++c) {
        if (fabs(vn[c]) > scale) scale = fabs(vn[c]);
    }
    return GAC_V_FLOOR + 1e-10 * scale;
}

/* Event value (what = 0), normal velocity (what = 1) or normal velocity + gac_v_round (what = 2) of contact c
 * at time t inside the step. */
static double gac_value_at(gac_sim *s, int what, int c, double t)
{
    const gac_model *md = s->model;
    gac_dense(s, t, s->xs);
    if (what == 0) {
        gac_events(s, t, s->xs, s->es);
        return s->es[c];
    }
    gac_normal_velocities(md, s->xs, s->p, s->es);
    return s->es[c] + (what == 2 ? gac_v_round(md, s->es) : 0.0);
}

/* Root in (a, b] of contact c's value_at(what) on the interpolant, value(a) > 0 >= value(b): Illinois,
 * then bisection. */
static double gac_locate(gac_sim *s, int what, int c, double a, double ga, double b, double gb)
{
    int side = 0, iter;
    for (iter = 0; iter < 200; ++iter) {
        double m, gm, tol = s->opt.event_tol + 4.0 * GAC_EPS * fabs(b);
        if (b - a <= tol) break;
        m = iter < 60 ? (a * gb - b * ga) / (gb - ga) : 0.5 * (a + b);
        if (!(m > a && m < b)) m = 0.5 * (a + b);
        gm = gac_value_at(s, what, c, m);
        if (gm > 0.0) {
            a = m; ga = gm;
            if (side == 1) gb *= 0.5;
            side = 1;
        } else {
            b = m; gb = gm;
            if (side == -1) ga *= 0.5;
            side = -1;
        }
    }
    return b;
}

/* A contact that starts the interval [t_a, t_b] at or beyond its wall (gap <= 0, just after an impact or
 * a release) and is approaching it at t_b (faster than gac_v_round) with gap(t_b) <= 0 has come back: if it
 * was leaving at t_a, the crossing follows the apex (root of the normal velocity), or is the apex itself
 * when the bounce is too small to open a positive gap; if it was not leaving, where its approach exceeds
 * gac_v_round. */
static double gac_locate_return(gac_sim *s, int c, double t_a, double t_b, double g_b)
{
    double v_a = gac_value_at(s, 1, c, t_a), v_b, t_apex, g_apex;
    if (!(v_a > 0.0)) {
        const double w_a = gac_value_at(s, 2, c, t_a);
        if (!(w_a > 0.0)) return t_a;
        return gac_locate(s, 2, c, t_a, w_a, t_b, gac_value_at(s, 2, c, t_b));
    }
    v_b = gac_value_at(s, 1, c, t_b);
    t_apex = gac_locate(s, 1, c, t_a, v_a, t_b, v_b);
    g_apex = gac_value_at(s, 0, c, t_apex);
    return g_apex > 0.0 ? gac_locate(s, 0, c, t_apex, g_apex, t_b, g_b) : t_apex;
}

/* The largest |coordinate| of the contact points at state x (m). */
static double gac_extent(const gac_sim *s, const double *x)
{
    const gac_model *md = s->model;
    double r[3 * md->npoint], l = 0.0;
    int i;
    md->contact_points(x, s->p, r);
    for (i = 0; i < 3 * md->npoint; ++i) {
        if (fabs(r[i]) > l) l = fabs(r[i]);
    }
    return l;
}

/* Depth (m) below which a gap minimum found between samples is a graze: the integrator's tolerance on
 * a position, atol + rtol l with l the largest |coordinate| of the contact points at state x (positions
 * are integrated to this, so a shallower dip cannot be told from a tangential touch); 0 for RK4, which has
 * no tolerance. */
static double gac_graze_depth(const gac_sim *s, const double *x)
{
    if (s->opt.method == GAC_METHOD_RK4) return 0.0;
    return s->opt.atol + s->opt.rtol * gac_extent(s, x);
}

/* A dip of contact c through its wall and back between two samples t_a < t_b at which its gap is > 0
 * (g_a, g_b) and its normal velocity (the gap rate, from the interpolated qd) goes from v_a < 0 to
 * v_b > 0: the gap's minimum is the root of the rate, searched like a crossing (Illinois, then bisection,
 * to event_tol).  As soon as the gap at an iterate is below -graze_depth, the wall crossing before it is
 * the event; as soon as it exceeds 2 (|v(a)| + |v(b)|) (b - a) - graze_depth on the rate's bracket [a, b],
 * the minimum cannot reach -graze_depth and there is none (so a minimum far from the wall costs a few
 * evaluations).  A minimum at gap >= -graze_depth (a touch with normal velocity 0, or within the
 * integration error of one) is a graze: no event.
 * Skipped, without evaluating anything, when the sampled rates cannot carry the gap to 0 inside the
 * interval: unless the rate overshoots its end values (it is nearly linear over a sample interval), the
 * minimum is at least max(g_a - |v_a| dt, g_b - v_b dt), and the test keeps a factor 2 on the speeds.
 * Returns 1 with the crossing in *t_cross, or 0. */
static int gac_dip(gac_sim *s, int c, double t_a, double g_a, double v_a, double t_b, double g_b,
                   double v_b, double *t_cross)
{
    const gac_model *md = s->model;
    double a = t_a, b = t_b, va = v_a, vb = v_b, fa = v_a, fb = v_b, depth = -1.0;
    int side = 0, iter;
    if (!(v_a < 0.0 && v_b > 0.0 && g_a > 0.0 && g_b > 0.0)) return 0;
    if (g_a >= -2.0 * v_a * (t_b - t_a) || g_b >= 2.0 * v_b * (t_b - t_a)) return 0;
    for (iter = 0; iter < 200; ++iter) {
        double m, gm, vm;
        if (b - a <= s->opt.event_tol + 4.0 * GAC_EPS * fabs(b)) break;
        m = iter < 60 ? (a * fb - b * fa) / (fb - fa) : 0.5 * (a + b);
        if (!(m > a && m < b)) m = 0.5 * (a + b);
        gac_dense(s, m, s->xs);
        md->contact_gaps(s->xs, s->p, s->es);
        gm = s->es[c];
        gac_normal_velocities(md, s->xs, s->p, s->es);
        vm = s->es[c];
        if (depth < 0.0) depth = gac_graze_depth(s, s->xs);
        if (gm < -depth) {
            *t_cross = gac_locate(s, 0, c, t_a, g_a, m, gm);
            return 1;
        }
        if (vm < 0.0) {
            a = m; va = fa = vm;
            if (side == 1) fb *= 0.5;
            side = 1;
        } else {
            b = m; vb = fb = vm;
            if (side == -1) fa *= 0.5;
            side = -1;
        }
        if (gm + depth >= 2.0 * (fabs(va) + fabs(vb)) * (b - a)) break;
    }
    return 0;
}

/* The contacts that may dip through their wall inside the step [s->t, t1] (not persistent, gap at the
 * step start below speed x the step, speed = 2 (|v(t0)| + |v(t1)|) from their normal velocities at the
 * step ends): cand[0..return-1], their speeds, and the normal velocities at the step start (v0).
 * Cheap when the chain is far from every wall: nothing is evaluated when every gap at the step start
 * exceeds 2 lever sum|qd| x the step (qd at both ends), because no point moves faster than lever sum|qd|
 * (lever = max(1 m, the chain's length): |dO/dq| is 1 for a translation and at most the chain's length for
 * a rotation).  The normal velocities at the step end are kept for the next step (s->vn). */
static int gac_dip_candidates(gac_sim *s, double t1, int *cand, double *speed, double *v0)
{
    const gac_model *md = s->model;
    int c, i, n = 0, nearby = 0;
    double bound = 0.0;
    for (i = 0; i < md->nq; ++i) bound += fabs(s->x[md->nq + i]) + fabs(s->x1[md->nq + i]);
    bound *= 2.0 * s->lever * (t1 - s->t);
    for (c = 0; c < md->ncontact && !nearby; ++c) nearby = !s->is_active[c] && s->ev[c] < bound;
    if (!nearby) {
        s->vn_valid = 0;
        return 0;
    }
    if (!s->vn_valid) gac_normal_velocities(md, s->x, s->p, s->vn);
    for (c = 0; c < md->ncontact; ++c) v0[c] = s->vn[c];
    gac_normal_velocities(md, s->x1, s->p, s->vn);
    s->vn_valid = 1;                             /* (gac_sim_advance clears it if x becomes anything else) */
    for (c = 0; c < md->ncontact; ++c) {
        speed[c] = 2.0 * (fabs(v0[c]) + fabs(s->vn[c]));
        if (!s->is_active[c] && s->ev[c] < speed[c] * (t1 - s->t)) cand[n++] = c;
    }
    return n;
}

/* Search the accepted step for the first event at event_samples points of the interpolant (the step ends
 * included), so that a dip through a wall and back inside one step is still seen.  Events: a wall
 * crossing (gap from > 0 to <= 0 between samples, or below 0 at a gap minimum between two samples where
 * it is > 0: a dip shorter than the sample spacing, see gac_dip); a contact that left its wall from gap <= 0
 * and is back at gap <= 0, approaching (a small bounce); a persistent contact's force from > 0 to <= 0.
 * Dips are looked for only for the step's candidates (gac_dip_candidates) in intervals whose gaps are both
 * below reach = speed x the interval (a contact farther from its wall cannot dip to it unless its normal
 * speed inside the step exceeds twice the sum of those at the step ends); only there are the normal
 * velocities at the samples evaluated.
 * Returns 1 with *t_event and *c_event, or 0; s->eprev ends as the event values at the step end. */
static int gac_find_event(gac_sim *s, double t1, double *t_event, int *c_event)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    int j, k, c, found = 0, have_prev = 1, ncand, cand[nc1];
    const int m = s->opt.event_samples;
    double t_prev = s->t, vprev[nc1], speed[nc1];
    gac_copy(s->eprev, s->ev, md->ncontact);
    ncand = gac_dip_candidates(s, t1, cand, speed, vprev);
    for (j = 1; j <= m && !found; ++j) {
        double tj = j == m ? t1 : s->t + (t1 - s->t) * (double)j / (double)m;
        double gj[nc1], vj[nc1];
        int have_v = 0;
        gac_dense(s, tj, s->xs);
        gac_events(s, tj, s->xs, gj);
        for (c = 0; c < md->ncontact; ++c) {           /* crossings and returns at the samples */
            double tc;
            if (gj[c] > 0.0) continue;
            if (s->eprev[c] > 0.0) {
                tc = gac_locate(s, 0, c, t_prev, s->eprev[c], tj, gj[c]);
            } else {
                if (s->is_active[c]) continue;
                if (!have_v) {
                    gac_dense(s, tj, s->xs);
                    gac_normal_velocities(md, s->xs, s->p, vj);
                    have_v = 1;
                }
                if (!(vj[c] < -gac_v_round(md, vj))) continue;
                tc = gac_locate_return(s, c, t_prev, tj, gj[c]);
            }
            if (!found || tc < *t_event) {
                *t_event = tc;
                *c_event = c;
            }
            found = 1;
        }
        for (k = 0; k < ncand; ++k) {                         /* dips between the samples */
            const double reach = speed[cand[k]] * (tj - t_prev);
            double tc;
            c = cand[k];
            if (!(s->eprev[c] > 0.0 && gj[c] > 0.0 && s->eprev[c] < reach && gj[c] < reach)) continue;
            if (!have_prev) {
                gac_dense(s, t_prev, s->xs);
                gac_normal_velocities(md, s->xs, s->p, vprev);
                have_prev = 1;
            }
            if (!have_v) {
                gac_dense(s, tj, s->xs);
                gac_normal_velocities(md, s->xs, s->p, vj);
                have_v = 1;
            }
            if (!gac_dip(s, c, t_prev, s->eprev[c], vprev[c], tj, gj[c], vj[c], &tc)) continue;
            if (!found || tc < *t_event) {
                *t_event = tc;
                *c_event = c;
            }
            found = 1;
        }
        gac_copy(s->eprev, gj, md->ncontact);
        if (have_v) gac_copy(vprev, vj, md->ncontact);
        have_prev = have_v;
        t_prev = tj;
    }
    return found;
}

static double gac_total_energy(const gac_model *md, const double *x, const double *p)
{
    double E[2];
    md->energy(x, x + md->nq, p, E);
    return E[0] + E[1];
}

/* Normal velocities (along the inward normals, m/s) of all contacts at state x. */
static void gac_normal_velocities(const gac_model *md, const double *x, const double *p, double *vn)
{
    double v[3 * md->npoint];
    int c;
    if (md->ncontact == 0) return;
    md->contact_velocities(x, x + md->nq, p, v);
    for (c = 0; c < md->ncontact; ++c) {
        const gac_contact *k = &md->contacts[c];
        vn[c] = (double)k->normal_sign * (k->kind == GAC_CONTACT_STOP ? x[md->nq + k->coordinate]
                                                                       : v[3 * (k->point - 1) + k->axis]);
    }
}

/* Normal accelerations (along the inward normals) of all contacts at time t and state x, with the contacts
 * set[0..n-1] held (n = 0: free flight). */
static int gac_normal_accelerations(gac_sim *s, double t, const double *x, int n, const int *set, double *an)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    double qdd[nq], lambda[nq], bias[GAC_AT_LEAST_1(md->njrow)];
    double *vel = GAC_WORK_VEL(md, s->work);
    const double *u = gac_input(s, t, x);
    int c, code = gac_constrained_dynamics(md, x, x + nq, u, s->p, n, set, qdd, lambda, s->work);
    if (code != GAC_OK) return code;
    md->contact_bias(x, x + nq, s->p, bias);
    md->contact_velocities(x, qdd, s->p, vel);           /* J qdd, read row by row */
    for (c = 0; c < md->ncontact; ++c) {
        int row;
        double sign;
        gac_contact_row(md, c, &row, &sign);
        an[c] = sign * (bias[row] + gac_row_value(md, c, qdd, vel));
    }
    return GAC_OK;
}

/* Add contact c to set[0..*n-1] if its constraint row is independent of theirs (N I_f^-1 N^T stays
 * positive definite): a dependent contact is held by the others already.  Returns GAC_OK or an error. */
static int gac_add_independent(gac_sim *s, const double *x, int *n, int *set, int c)
{
    const gac_model *md = s->model;
    double v[md->nq], e[md->nq];
    double *A = GAC_WORK_A(md, s->work);
    int code;
    if (*n == md->nq) return GAC_OK;
    set[*n] = c;
    code = gac_impact_system(md, x, x + md->nq, s->p, *n + 1, set, s->work, v, e);
    if (code != GAC_OK) return code;
    if (gac_ldlt(*n + 1, A, 1e-12) == 0) ++*n;
    return GAC_OK;
}

/* Project the state x onto the contacts set[0..n-1] held at their walls: (positions = 1) the gaps to
 * s->gap_held (the gap each had when it landed) by Newton steps dq = -Y (N Y)^-1 (g - g_held)
 * (Y = I_f^-1 N^T, the smallest correction in the mass metric), a contact outside the set that the
 * correction would push deeper into its wall being held where it is (an active set); then the normal
 * velocities to 0, qd -= Y (N Y)^-1 N qd: a plastic impact, so the kinetic energy cannot grow. */
static int gac_project(gac_sim *s, double *x, int n, const int *set, int positions)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    const int nq = md->nq;
    const double floor = 1e-6 * s->opt.contact_tol + 1e-15;
    double v[nq], e[nq], g[nc1], g0[nc1];
    double corr[nq], target[nq];
    double *Y = GAC_WORK_Y(md, s->work), *A = GAC_WORK_A(md, s->work);
    int held[nq], in_set[nc1], a, c, i, it, code, m = n;
    if (n == 0) return GAC_OK;
    g[0] = g0[0] = 0.0;
    md->contact_gaps(x, s->p, g0);
    for (c = 0; c < md->ncontact; ++c) in_set[c] = 0;
    for (a = 0; a < n; ++a) {
        held[a] = set[a];
        in_set[set[a]] = 1;
        target[a] = s->gap_held[set[a]];
    }
    for (it = 0; positions && it < 4 + md->ncontact; ++it) {
        double gmax = 0.0;
        int added = 0;
        md->contact_gaps(x, s->p, g);
        for (c = 0; c < md->ncontact && it > 0; ++c) {      /* pushed deeper: hold it */
            const double stay = g0[c] < 0.0 ? g0[c] : 0.0;
            if (!in_set[c] && g[c] < stay - floor && m < nq) {
                in_set[c] = 1;
                target[m] = stay;
                held[m++] = c;
                added = 1;
            }
        }
        for (a = 0; a < m; ++a) {
            g[held[a]] -= target[a];
            if (fabs(g[held[a]]) > gmax) gmax = fabs(g[held[a]]);
        }
        if (gmax <= floor && !added) break;
        if (it >= 4 && !added) break;
        code = gac_impact_system(md, x, x + nq, s->p, m, held, s->work, v, e);
        if (code != GAC_OK) return code;
        if (gac_ldlt_drop(m, A, 1e-12) < 0) return GAC_ERR_SINGULAR_CONTACT;
        for (a = 0; a < m; ++a) corr[a] = -g[held[a]];
        gac_ldlt_solve(m, A, corr);
        for (i = 0; i < nq; ++i) {
            for (a = 0; a < m; ++a) x[i] += Y[a*nq + i] * corr[a];
        }
    }
    code = gac_impact_system(md, x, x + nq, s->p, n, set, s->work, v, e);
    if (code != GAC_OK) return code;
    if (gac_ldlt_drop(n, A, 1e-12) < 0) return GAC_ERR_SINGULAR_CONTACT;
    for (a = 0; a < n; ++a) corr[a] = -v[a];
    gac_ldlt_solve(n, A, corr);
    for (i = 0; i < nq; ++i) {
        for (a = 0; a < n; ++a) x[nq + i] += Y[a*nq + i] * corr[a];
    }
    return GAC_OK;
}

/* Of the contacts set[0..*n-1] (at their walls, normal velocities 0), keep those that push in the
 * acceleration-level complementarity problem: lambda >= 0, normal acceleration w = A lambda + c >= 0,
 * lambda_i w_i = 0, with A = N I_f^-1 N^T and c = N qdd_free + Ndot qd.  Solved exactly by enumerating the
 * pushing sets, as the impact's complementarity form.  The set is reduced in place. */
static int gac_settle(gac_sim *s, double t, const double *x, int *n, int *set)
{
    const gac_model *md = s->model;
    const int nq = md->nq, m = *n;
    double v[nq], e[nq], c[nq], qdd[nq], bias[GAC_AT_LEAST_1(md->njrow)];
    double Asub[GAC_LCP_CAP * GAC_LCP_CAP], rhs[nq], scale = 0.0;   /* m <= GAC_LCP_CAP (below) */
    double *A = GAC_WORK_A(md, s->work), *vel = GAC_WORK_VEL(md, s->work);
    int a, b, code;
    unsigned long mask, full;
    if (m == 0) return GAC_OK;
    if (m > GAC_MAX_LCP(md)) return GAC_ERR_LCP;
    md->forward_dynamics(x, x + nq, gac_input(s, t, x), s->p, qdd);
    code = gac_impact_system(md, x, x + nq, s->p, m, set, s->work, v, e);
    if (code != GAC_OK) return code;
    md->contact_bias(x, x + nq, s->p, bias);
    md->contact_velocities(x, qdd, s->p, vel);           /* J qdd_free, read row by row */
    for (a = 0; a < m; ++a) {
        int row;
        double sign;
        gac_contact_row(md, set[a], &row, &sign);
        c[a] = sign * (bias[row] + gac_row_value(md, set[a], qdd, vel));
        if (fabs(c[a]) > scale) scale = fabs(c[a]);
    }
    full = (1UL << m) - 1UL;
    for (mask = full; ; --mask) {
        int idx[nq], k = 0, ok = 1;
        for (a = 0; a < m; ++a) {
            if (mask & (1UL << a)) idx[k++] = a;
        }
        for (a = 0; a < k; ++a) {
            for (b = 0; b < k; ++b) Asub[a*k + b] = A[idx[a]*m + idx[b]];
            rhs[a] = -c[idx[a]];
        }
        if (k > 0 && gac_ldlt(k, Asub, 1e-12) != 0) ok = 0;
        if (ok && k > 0) gac_ldlt_solve(k, Asub, rhs);
        for (a = 0; ok && a < k; ++a) {
            if (rhs[a] < -1e-12 * (scale + 1e-300)) ok = 0;
        }
        for (a = 0; ok && a < m; ++a) {               /* w = A lambda + c >= 0 for the others */
            double w = c[a];
            if (mask & (1UL << a)) continue;
            for (b = 0; b < k; ++b) w += A[a*m + idx[b]] * rhs[b];
            if (w < -1e-10 * (scale + 1e-300)) ok = 0;
        }
        if (ok) {
            for (a = 0; a < k; ++a) set[a] = set[idx[a]];
            *n = k;
            return GAC_OK;
        }
        if (mask == 0) break;
    }
    return GAC_ERR_LCP;
}

/* Bring the contacts set[0..nset-1] to rest (normal velocity 0: bilateral, impulse of either sign, the
 * resting constraint) while no other contact of list[0..n-1] is driven into its wall (impulse >= 0,
 * complementary to its normal velocity >= 0): the projection of qd onto that convex set in the mass
 * metric, so the kinetic energy cannot grow.  Solved exactly by enumerating the pushing sets of the others
 * (as gac_lcp).  Only the others whose rows are independent of the set's take part (a dependent one moves
 * with them). */
static int gac_hold(gac_sim *s, double *x, int nset, const int *set, int n, const int *list)
{
    const gac_model *md = s->model;
    const int nq = md->nq;
    double v[nq], e[nq], rhs[nq], F[nq];
    double *Asub = s->sub;                         /* up to nq x nq */
    double *Y = GAC_WORK_Y(md, s->work), *A = GAC_WORK_A(md, s->work);
    double scale = 0.0;
    int all[nq], m = nset, a, b, i, k, code, uni;
    unsigned long mask;
    for (a = 0; a < nset; ++a) all[a] = set[a];
    for (k = 0; k < n; ++k) {                  /* the others, independent ones only */
        int member = 0;
        for (a = 0; a < nset; ++a) member |= set[a] == list[k];
        if (member) continue;
        code = gac_add_independent(s, x, &m, all, list[k]);
        if (code != GAC_OK) return code;
    }
    uni = m - nset;
    if (uni > GAC_MAX_LCP(md)) return GAC_ERR_LCP;
    code = gac_impact_system(md, x, x + nq, s->p, m, all, s->work, v, e);
    if (code != GAC_OK) return code;
    for (a = 0; a < m; ++a) {
        if (fabs(v[a]) > scale) scale = fabs(v[a]);
    }
    for (mask = (1UL << uni) - 1UL; ; --mask) {        /* the others that push, largest sets first */
        int idx[nq], kk = 0, ok = 1;
        for (a = 0; a < nset; ++a) idx[kk++] = a;
        for (a = 0; a < uni; ++a) {
            if (mask & (1UL << a)) idx[kk++] = nset + a;
        }
        for (a = 0; a < kk; ++a) {
            for (b = 0; b < kk; ++b) Asub[a*kk + b] = A[idx[a]*m + idx[b]];
            rhs[a] = -v[idx[a]];
        }
        if (kk > 0 && gac_ldlt(kk, Asub, 1e-12) != 0) ok = 0;
        if (ok && kk > 0) gac_ldlt_solve(kk, Asub, rhs);
        for (a = 0; ok && a < m; ++a) F[a] = 0.0;
        for (a = 0; ok && a < kk; ++a) {
            if (idx[a] >= nset && rhs[a] < 0.0) ok = 0;
            F[idx[a]] = rhs[a];
        }
        for (a = nset; ok && a < m; ++a) {             /* the others' normal velocities afterwards >= 0 */
            double w = v[a];
            for (b = 0; b < m; ++b) w += A[a*m + b] * F[b];
            if (w < -1e-10 * (scale + 1e-300)) ok = 0;
        }
        if (ok) {
            for (i = 0; i < nq; ++i) {
                for (a = 0; a < m; ++a) x[nq + i] += Y[a*nq + i] * F[a];
            }
            return GAC_OK;
        }
        if (mask == 0) break;
    }
    return GAC_ERR_LCP;
}

/* Make set[0..n-1] the persistent contacts; record (if not NULL) lists the activations and releases. */
static void gac_set_active(gac_sim *s, int n, const int *set, gac_impact_record *r)
{
    const gac_model *md = s->model;
    int now[GAC_AT_LEAST_1(md->ncontact)], a, c;
    for (c = 0; c < md->ncontact; ++c) now[c] = 0;
    for (a = 0; a < n; ++a) now[set[a]] = 1;
    if (r) {
        r->nactivated = r->nreleased = 0;
        for (a = 0; a < n; ++a) {
            if (!s->is_active[set[a]]) r->activated[r->nactivated++] = set[a];
        }
        for (a = 0; a < s->nactive; ++a) {
            if (!now[s->active[a]]) r->released[r->nreleased++] = s->active[a];
        }
        s->n_activations += r->nactivated;
        s->n_releases += r->nreleased;
    }
    for (c = 0; c < md->ncontact; ++c) s->is_active[c] = now[c];
    for (a = 0; a < n; ++a) s->active[a] = set[a];
    s->nactive = n;
}

/* gac_sim_init: contacts that start at their wall (|gap| <= contact_tol) with a normal velocity whose bounce
 * would rise less than rest_height (under the largest free-flight normal acceleration of any contact, so
 * that a contact pressed only through the others, like the top of a ladder, counts) become persistent:
 * positions and velocities projected, then only those with a pushing force kept. */
static int gac_rest_at_start(gac_sim *s)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    double gaps[nc1], vn[nc1], an[nc1], a = 0.0;
    int set[md->nq], n = 0, c, code;
    md->contact_gaps(s->x, s->p, gaps);
    gac_normal_velocities(md, s->x, s->p, vn);
    code = gac_normal_accelerations(s, s->t, s->x, 0, 0, an);
    if (code != GAC_OK) return code;
    for (c = 0; c < md->ncontact; ++c) {
        if (fabs(an[c]) > a) a = fabs(an[c]);
    }
    for (c = 0; c < md->ncontact; ++c) {
        if (fabs(gaps[c]) <= s->opt.contact_tol && vn[c] * vn[c] <= 2.0 * a * s->rest_height) {
            code = gac_add_independent(s, s->x, &n, set, c);
            if (code != GAC_OK) return code;
        }
    }
    if (n == 0) return GAC_OK;
    for (c = 0; c < n; ++c) s->gap_held[set[c]] = gaps[set[c]];         /* held where they start */
    code = gac_project(s, s->x, n, set, 0);
    if (code == GAC_OK) code = gac_settle(s, s->t, s->x, &n, set);
    if (code != GAC_OK) return code;
    s->n_activations += n;
    gac_set_active(s, n, set, 0);
    s->pending = n > 0;
    return GAC_OK;
}

/* The round-off bound of the impact law on the kinetic energy, relative to T (the velocities qd -> qd_plus
 * at T = T(qd); work holds the rows Y_a = I_f^-1 n_a as left by gac_impact_system).  The law's solves are
 * backward stable: they are exact for I_f + dI_f with |dI_f| <= 4 (nq + 1) eps |I_f|, and the energy they
 * leave differs from the law's by dI_f's work on the velocities, |qd^T dI_f dqd| + |dqd^T dI_f dqd| / 2
 * (dqd = qd_plus - qd).  So b = max(1e-10, 4 (nq + 1) eps |I_f| (|qd| |dqd| + |dqd|^2 / 2) / T), |I_f|
 * (2-norm) by 16 power iterations with the model's I_f v (generalized_momentum, O(n) each), with |dqd| taken
 * as sum_a |F_a| |I_f^-1 n_a| when the contacts' changes cancel (nearly dependent contacts pushing against
 * each other).  The energies the post-conditions compare are themselves evaluated with an error of about
 * (nq + 1) eps |I_f| |v|^2 / 2 at velocities v, so b also holds (nq + 1) eps |I_f| (|qd|^2 + |qd_plus|^2) / (2 T)
 * (far below 1e-10 unless the velocities lie along a soft direction of I_f).  b grows where a large velocity
 * change meets a soft direction of I_f (a slender link with a tiny axial inertia, a state near the gimbal
 * lock). */
static double gac_impact_roundoff(const gac_model *md, const double *q, const double *p, const double *work, int n,
                                  const double *F, const double *qd, const double *qd_plus, double T)
{
    const int nq = md->nq;
    const double *Y = GAC_WORK_Y(md, work);
    double x[nq], y[nq], norm_M = 0.0, size = 0.0, change = 0.0, parts = 0.0, after = 0.0, b;
    int a, i, it;
    for (i = 0; i < nq; ++i) {
        x[i] = 1.0 + 0.1 * i * (i % 2 ? -1.0 : 1.0);      /* a fixed, generic start */
        size += qd[i] * qd[i];
        after += qd_plus[i] * qd_plus[i];
        change += (qd_plus[i] - qd[i]) * (qd_plus[i] - qd[i]);
    }
    for (a = 0; a < n; ++a) {                            /* sum |F_a| |Y_a|: the changes before they cancel */
        double column = 0.0;
        for (i = 0; i < nq; ++i) column += Y[a*nq + i] * Y[a*nq + i];
        parts += fabs(F[a]) * sqrt(column);
    }
    for (it = 0; it < 16; ++it) {                        /* |I_f| by power iteration */
        double sum = 0.0;
        for (i = 0; i < nq; ++i) sum += x[i] * x[i];
        sum = sqrt(sum);
        if (!(sum > 0.0)) break;
        for (i = 0; i < nq; ++i) y[i] = x[i] / sum;
        md->generalized_momentum(q, y, p, x);            /* x = I_f y */
        norm_M = 0.0;
        for (i = 0; i < nq; ++i) norm_M += x[i] * x[i];
        norm_M = sqrt(norm_M);
    }
    b = (nq + 1) * GAC_EPS * norm_M * 0.5 * (size + after);          /* evaluating T before and after */
    size = sqrt(size);
    change = sqrt(change) > parts ? sqrt(change) : parts;
    b += 4.0 * (nq + 1) * GAC_EPS * norm_M * (size * change + 0.5 * change * change);
    b /= T > 0.0 ? T : 1e-300;
    return b > 1e-10 ? b : 1e-10;
}

/* The smallest chart measure at which the run's results keep its tolerance: impacts and accelerations
 * computed with I_f carry a relative error of about 16 eps / mu^2 from the chart alone, so
 * mu_min = sqrt(16 eps / tol), tol = rtol (adaptive) or 1e-10 (RK4).  Below it the loop stops with
 * GAC_ERR_GIMBAL_LOCK (continue on another chart). */
static double gac_chart_floor(const gac_sim *s)
{
    const double tol = s->opt.method == GAC_METHOD_RK4 || s->opt.rtol > 1e-6 ? 1e-10 : s->opt.rtol;
    return sqrt(16.0 * GAC_EPS / (tol < 1e-12 ? 1e-12 : tol));
}

/* Gap (m) within which an approaching contact joins an impact located on another contact: contact_tol, or
 * for the adaptive methods 100 times their position tolerance (atol + rtol l, l the largest |coordinate|
 * of the contact points) if larger.  Impacts that the exact motion makes simultaneous (a symmetric pair)
 * arrive split by the integration error, which accumulates over the steps to about this much. */
static double gac_simultaneity_window(const gac_sim *s, const double *x)
{
    const double w = 100.0 * gac_graze_depth(s, x);
    return w > s->opt.contact_tol ? w : s->opt.contact_tol;
}

/* Resolve the impact at state s->xs (time t).
 * Who takes part: every contact within contact_tol of its wall (c_event whatever its gap), every
 * approaching contact within the simultaneity window, and every persistent contact, approaching ones
 * first (at most nq).  It is an impact when a contact that is not
 * persistent approaches its wall there faster than gac_v_round (or c_event came back to it at its apex) and
 * either an impulse is applied or the persistent set changes; else a graze (returns 0).
 * The law: gac_impact_rounds (Newton's law, Eq. 47, with complementarity, in rounds until no contact
 * approaches; a contact that rests or separates takes an impulse only when the others drive it into its
 * wall).
 * Resting contact: a contact that approaches a wall with e < 1 and whose bounce would rise less than h
 * ((e v-)^2 <= 2 a h, a = its normal acceleration towards the wall with the persistent contacts held;
 * h = rest_height, but never below the resolution of the positions, graze_depth + 16 eps l, unless both
 * rules are off), or that has had zeno_impacts impacts at shrinking intervals, lands: it is struck with
 * e = 0 (a plastic impact: F >= 0, no pull); r->energy_rest is the kinetic energy the landings take (the
 * law with every contact's own e minus the law with the landings plastic).  On a wall with e = 1 a
 * contact lands only if it arrives at rest: v-^2 <= 2 a h and its landing takes no more than the
 * round-off bound of the energy, so that an elastic chain keeps its energy.  Persistent contacts take part
 * with their own e (at rest it does not matter; one driven into its wall in a later round bounces).
 * Landing and persistent contacts that end at rest (normal velocity below round-off) form the new
 * persistent set (independent rows only, held at their landing gap, only those that push kept), and so
 * does a persistent contact of a wall with e < 1 that the impact lifts by less than h (a bounce the rest
 * rule would end: its lift velocity is removed with the others' round-off, a bilateral resting
 * constraint, not an impact impulse; the energy it takes is in energy_rest); one lifted higher is
 * released.  The set is brought to rest by gac_hold, which drives no other contact into its wall.
 * Post-conditions, checked here (GAC_ERR_IMPACT_ACCURACY if one fails), to the law's round-off bound b
 * (gac_impact_roundoff, 1e-10 for a well-conditioned I_f): every impulse >= 0; no contact within contact_tol
 * of its wall approaches it faster than 10 b max|v-| + 1e-15 m/s; the kinetic energy does not grow by
 * more than b T and, when every contact that takes an impulse has e = 1, changes by at most b T.  The state
 * after the impact is in s->x1.  Returns 1 (impact applied), 0 (graze) or an error. */
static int gac_resolve(gac_sim *s, double t, int c_event, gac_impact_record *r)
{
    const gac_model *md = s->model;
    const int nc1 = GAC_AT_LEAST_1(md->ncontact);
    const int nq = md->nq;
    double gaps[nc1], vn[nc1], an[nc1];
    double e[nq], e_law[nq], qd_plus[nq], F[nq], E[2];
    double scale = 0.0, v_hold, v_rest, approach_tol, T_before, T_after, T_law, bound, height = 0.0, window;
    int list[nq], landing[nq], shrinking[nc1], set[nq];
    int c, i, k, pass, n = 0, nset = 0, impact = 0, elastic = 1, changed = 0, first = -1, code, rounds, plastic;
    double *x = s->xs;
    md->contact_gaps(x, s->p, gaps);
    gac_normal_velocities(md, x, s->p, vn);
    r->ncontact = 0;
    r->nactivated = r->nreleased = 0;
    r->rounds = r->plastic = r->law_elastic = 0;
    r->energy_rest = 0.0;
    r->roundoff = 1e-10;
    v_rest = gac_v_round(md, vn);
    for (c = 0; c < md->ncontact; ++c) {
        if (fabs(vn[c]) > scale) scale = fabs(vn[c]);
        if (!s->is_active[c] && (((c == c_event || gaps[c] <= s->opt.contact_tol) && vn[c] < -v_rest)
                                 || (c == c_event && gaps[c] <= 0.0 && vn[c] <= 0.0)))   /* back at the apex */
            impact = 1;
    }
    if (!impact) return 0;                               /* grazing touch: nothing to resolve */
    {
        /* every other point must be on the right side of its wall, to the event search's tolerance */
        const double depth = s->opt.contact_tol + gac_simultaneity_window(s, x);
        for (c = 0; c < md->ncontact; ++c) {
            if (gaps[c] < -depth) return GAC_ERR_LOST_CONTACT;
        }
    }
    if (gac_chart_measure(md, x) < gac_chart_floor(s)) return GAC_ERR_GIMBAL_LOCK;
    window = gac_simultaneity_window(s, x);
    for (pass = 0; pass < 3; ++pass) {                   /* approaching, then at rest, then separating */
        for (c = 0; c < md->ncontact; ++c) {
            const int near = s->is_active[c] || c == c_event || gaps[c] <= s->opt.contact_tol
                             || (vn[c] < -v_rest && gaps[c] <= window);
            const int kind = vn[c] < 0.0 ? 0 : vn[c] == 0.0 ? 1 : 2;
            if (!near || kind != pass) continue;
            if (n == nq) {
                if (pass == 0) return GAC_ERR_TOO_MANY_CONTACTS;
                continue;                                /* resting or leaving: the others hold it */
            }
            if (c == c_event) first = n;
            list[n++] = c;
        }
    }
    r->t = t;
    md->energy(x, x + nq, s->p, E);
    T_before = E[0];
    if (!gac_finite(E, 2)) return GAC_ERR_NONFINITE;
    r->energy_before = E[0] + E[1];
    for (i = 0; i < nq; ++i) {
        r->q[i] = x[i];
        r->qd_before[i] = x[nq + i];
    }
    /* who lands */
    for (c = 0; c < md->ncontact; ++c) {
        an[c] = 0.0;
        /* impacts of c at shrinking intervals */
        shrinking[c] = s->dt_last[c] >= 0.0 && t - s->t_last[c] <= s->dt_last[c];
    }
    if (s->rest_height > 0.0 || s->opt.zeno_impacts > 0) {
        const double floor = gac_graze_depth(s, x) + 16.0 * GAC_EPS * gac_extent(s, x);
        height = s->rest_height > floor ? s->rest_height : floor;
        code = gac_normal_accelerations(s, t, x, s->nactive, s->active, an);
        if (code != GAC_OK) return code;
    }
    for (k = 0; k < n; ++k) {
        c = list[k];
        e_law[k] = e[k] = gac_restitution(md, s->p, c);
        landing[k] = s->is_active[c];                 /* a persistent contact stays if it ends at rest */
        if (s->is_active[c]) {
            /* its own e: at rest (v = 0) e does not matter; driven into its wall in a later round, it bounces */
        } else if (vn[c] <= 0.0 && gaps[c] <= s->opt.contact_tol) {
            const double reach = 2.0 * (-an[c]) * height;   /* v^2 of a bounce that rises that high */
            const double bounce = e_law[k] < 1.0 ? e_law[k] * vn[c] : vn[c];   /* e = 1: arrived at rest */
            const int rests = an[c] < 0.0 && bounce * bounce <= reach;
            const int zeno = e_law[k] < 1.0 && s->opt.zeno_impacts > 0 && shrinking[c]
                             && s->n_shrink[c] + 1 >= s->opt.zeno_impacts;
            if (rests || zeno) {
                landing[k] = 1;
                e[k] = 0.0;
            }
        }
    }
    /* the law with every contact's own e, then (if some contact lands) with the landings plastic; a landing
     * on a wall with e = 1 is kept only if it takes no more than round-off energy (it arrived at rest) */
    code = gac_impact_rounds(md, x, x + nq, s->p, n, list, e_law, first, qd_plus, F, s->work, &rounds,
                                   &plastic);
    if (code != GAC_OK) return code;
    bound = r->roundoff = gac_impact_roundoff(md, x, s->p, s->work, n, F, x + nq, qd_plus, T_before);
    md->energy(x, qd_plus, s->p, E);
    T_law = E[0];
    r->law_elastic = !plastic;                   /* contacts on walls with e < 1 may take part, without impulse */
    for (k = 0; k < n; ++k) {
        if (F[k] > 0.0 && e_law[k] != 1.0) r->law_elastic = 0;
    }
    if (r->law_elastic && fabs(T_law - T_before) > bound * T_before) return GAC_ERR_IMPACT_ACCURACY;
    for (k = 0; k < n; ++k) changed |= e[k] != e_law[k];
    for (pass = 0; changed && pass < 2; ++pass) {
        int elastic_landing = 0;
        code = gac_impact_rounds(md, x, x + nq, s->p, n, list, e, first, qd_plus, F, s->work, &rounds,
                                       &plastic);
        if (code != GAC_OK) return code;
        md->energy(x, qd_plus, s->p, E);
        for (k = 0; k < n; ++k) {
            if (landing[k] && !s->is_active[list[k]] && e_law[k] == 1.0 && T_law - E[0] > bound * T_before) {
                landing[k] = 0;
                e[k] = 1.0;
                elastic_landing = 1;
            }
        }
        if (!elastic_landing) break;
    }
    r->rounds = rounds;
    r->plastic = plastic;
    for (i = 0; i < nq; ++i) {
        s->x1[i] = x[i];
        s->x1[nq + i] = qd_plus[i];
    }
    md->energy(s->x1, s->x1 + nq, s->p, E);
    T_after = E[0];
    r->energy_rest = T_law - T_after;
    /* the record: the contacts that approached or took an impulse */
    r->complementarity = rounds > 1;
    for (k = 0; k < n; ++k) {
        c = list[k];
        if (F[k] > 0.0 || (!s->is_active[c] && vn[c] < 0.0)) {
            r->contact[r->ncontact] = c;
            r->impulse[r->ncontact++] = F[k];
            if (!(F[k] > 0.0) || !(vn[c] < 0.0)) r->complementarity = 1;
            if (F[k] > 0.0 && e[k] != 1.0) elastic = 0;
        }
        if (F[k] < 0.0) return GAC_ERR_IMPACT_ACCURACY;
    }
    /* post-conditions of the law (kinetic energy at the impact configuration), to its round-off bound */
    if (T_after > T_before * (1.0 + bound) + 1e-300) return GAC_ERR_IMPACT_ACCURACY;
    if (elastic && !plastic && fabs(T_after - T_before) > bound * T_before) return GAC_ERR_IMPACT_ACCURACY;
    /* the persistent set: landing and persistent contacts that end at rest */
    gac_normal_velocities(md, s->x1, s->p, vn);
    v_hold = 1e-9 * scale;                          /* at rest, to the law's round-off */
    for (k = 0; k < n; ++k) {
        c = list[k];
        /* a persistent contact that the impact lifts by less than h stays (its small lift velocity, what the
         * bounces of the accumulation it stands for would carry, is removed with the others') */
        int held_lift = 0;
        if (s->is_active[c] && vn[c] > v_hold && e_law[k] < 1.0 && height > 0.0) {
            /* its acceleration towards the wall with the other persistent contacts held */
            double a_free[nc1];
            int others[nq], m = 0, a;
            for (a = 0; a < s->nactive; ++a) {
                if (s->active[a] != c) others[m++] = s->active[a];
            }
            code = gac_normal_accelerations(s, t, s->x1, m, others, a_free);
            if (code != GAC_OK) return code;
            held_lift = a_free[c] < 0.0 && vn[c] * vn[c] <= 2.0 * (-a_free[c]) * height;
        }
        if ((landing[k] && vn[c] <= v_hold) || held_lift) {
            code = gac_add_independent(s, s->x1, &nset, set, list[k]);
            if (code != GAC_OK) return code;
        }
    }
    if (nset > 0) {
        for (k = 0; k < nset; ++k) {  /* a landing contact is held at the gap it landed at: the configuration */
            if (!s->is_active[set[k]]) s->gap_held[set[k]] = gaps[set[k]];   /* stays, so V does too */
        }
        code = gac_hold(s, s->x1, nset, set, n, list);   /* held at rest, the others not pushed in */
        if (code == GAC_OK) code = gac_settle(s, t, s->x1, &nset, set);
        if (code != GAC_OK && code != GAC_ERR_LCP) return code;
        gac_normal_velocities(md, s->x1, s->p, vn);
        for (k = 0; k < n; ++k) {
            /* a contact whose row is (nearly) dependent on the held ones' moves with them: if holding them
             * drives it into its wall, or the contacts are too degenerate to say which push, nothing is
             * held this time (the law's velocities stand) */
            if (code == GAC_ERR_LCP || vn[list[k]] < -(10.0 * bound * scale + 1e-15)) {
                for (i = 0; i < nq; ++i) s->x1[nq + i] = qd_plus[i];
                nset = 0;
                break;
            }
        }
        gac_normal_velocities(md, s->x1, s->p, vn);
        if (nset > 0) {          /* holding them changed the velocities too: the bound covers the whole change */
            const double held = gac_impact_roundoff(md, x, s->p, s->work, 0, F, x + nq, s->x1 + nq, T_before);
            if (held > bound) bound = r->roundoff = held;
        }
    }
    if (rounds == 0) {                               /* no impulse: an impact only if a contact lands */
        int same = nset == s->nactive;
        for (k = 0; same && k < nset; ++k) same = s->is_active[set[k]];
        if (same) return 0;
    }
    for (i = 0; i < nq; ++i) r->qd_after[i] = s->x1[nq + i];
    md->energy(x, s->x1 + nq, s->p, E);          /* at the impact configuration, as T_law */
    r->energy_rest = T_law > E[0] ? T_law - E[0] : 0.0; /* (a landing may also leave more than the law) */
    r->energy_after = gac_total_energy(md, s->x1, s->p);
    r->approach_after = 0.0;                  /* fastest approach of a contact at its wall, afterwards */
    for (c = 0; c < md->ncontact; ++c) {
        if (gaps[c] <= s->opt.contact_tol && -vn[c] > r->approach_after) r->approach_after = -vn[c];
    }
    r->approach_before = scale;
    approach_tol = 10.0 * bound * scale + 1e-15;
    if (r->approach_after > approach_tol) return GAC_ERR_IMPACT_ACCURACY;
    for (k = 0; k < r->ncontact; ++k) {                    /* impact history of each new contact */
        c = r->contact[k];
        if (s->is_active[c]) continue;
        s->n_shrink[c] = shrinking[c] ? s->n_shrink[c] + 1 : 0;
        s->dt_last[c] = s->dt_last[c] < -1.5 ? -1.0 : t - s->t_last[c];
        s->t_last[c] = t;
    }
    gac_set_active(s, nset, set, r);
    return 1;
}

/* Release the persistent contact c_event, whose force fell to 0 at state s->xs (time t); any other
 * persistent contact that would then pull goes too.  Fills the record (no impact: ncontact = 0). */
static int gac_release(gac_sim *s, double t, int c_event, gac_impact_record *r)
{
    const gac_model *md = s->model;
    int set[md->nq], n = 0, a, i, code;
    for (a = 0; a < s->nactive; ++a) {
        if (s->active[a] != c_event) set[n++] = s->active[a];
    }
    code = gac_settle(s, t, s->xs, &n, set);
    if (code != GAC_OK) return code;
    r->t = t;
    r->ncontact = 0;
    r->complementarity = 0;
    r->energy_before = r->energy_after = gac_total_energy(md, s->xs, s->p);
    for (i = 0; i < md->nq; ++i) {
        r->q[i] = s->xs[i];
        r->qd_before[i] = r->qd_after[i] = s->xs[md->nq + i];
    }
    r->approach_before = r->approach_after = 0.0;
    gac_set_active(s, n, set, r);
    return GAC_OK;
}

/* Add the work of the inputs, the dissipation of the dampers and (with resting contacts on walls with friction)
 * that of sliding friction over [s->t, t_b] of the current step to s->work_input, s->work_damping and
 * s->work_friction: 5-point Gauss-Legendre (exact for polynomials of degree 9) on the step's dense output. */
static void gac_add_work(gac_sim *s, double t_b)
{
    static const double node[5] = {0.04691007703066800, 0.23076534494715845, 0.5, 0.76923465505284155,
                                   0.95308992296933200};
    static const double weight[5] = {0.11846344252809454, 0.23931433524968324, 0.28444444444444444,
                                     0.23931433524968324, 0.11846344252809454};
    const gac_model *md = s->model;
    const double h = t_b - s->t;
    const int friction = s->nactive > 0 && gac_has_friction(md);
    double x[md->nx], P[2], w_in = 0.0, w_damp = 0.0, w_friction = 0.0;
    int j;
    if ((md->power == 0 && !friction) || !(h > 0.0)) return;
    for (j = 0; j < 5; ++j) {
        const double t = s->t + node[j] * h;
        gac_dense(s, t, x);
        if (md->power != 0) {
            md->power(x, x + md->nq, gac_input(s, t, x), s->p, P);
            w_in += weight[j] * P[0];
            w_damp += weight[j] * P[1];
        }
        if (friction) {
            double qdd[md->nq], lambda[md->nq], D = 0.0;
            if (gac_constrained_dynamics_friction(md, x, x + md->nq, gac_input(s, t, x), s->p, s->nactive, s->active,
                                                  qdd, lambda, s->work, &D) == GAC_OK)
                w_friction += weight[j] * D;
        }
    }
    s->work_input += h * w_in;
    s->work_damping += h * w_damp;
    s->work_friction += h * w_friction;
}

int gac_sim_set_input(gac_sim *s, const double *u)
{
    int i;
    if (s == 0 || (u == 0 && s->model->nu > 0)) return GAC_ERR_NULL_ARGUMENT;
    if (!gac_finite(u, s->model->nu)) return GAC_ERR_BAD_INPUT;
    for (i = 0; i < s->model->nu; ++i) s->u[i] = u[i];
    s->f_valid = 0;                    /* the flight derivative and the resting contacts' forces change */
    s->input_changed = 1;
    return GAC_OK;
}

int gac_sim_set_controller(gac_sim *s, gac_controller controller, void *user)
{
    if (s == 0) return GAC_ERR_NULL_ARGUMENT;
    s->controller = controller;
    s->controller_data = user;
    s->f_valid = 0;
    s->input_changed = 1;
    return GAC_OK;
}

/* After the inputs changed: release the resting contacts that the new inputs pull off their walls (their
 * force lambda <= 0 at the current state).  Returns 1 (record filled: GAC_SIM_CONTACT), 0 or an error. */
static int gac_recheck_rest(gac_sim *s, gac_impact_record *record)
{
    const gac_model *md = s->model;
    int a, code;
    s->input_changed = 0;
    if (s->nactive == 0) return 0;
    gac_events(s, s->t, s->x, s->ev);
    if (s->fail) return s->fail;
    for (a = 0; a < s->nactive; ++a) {
        if (s->ev[s->active[a]] <= 0.0) break;
    }
    if (a == s->nactive) return 0;
    gac_copy(s->xs, s->x, md->nx);
    code = gac_release(s, s->t, s->active[a], record);
    if (code < 0) return code;
    s->f_valid = s->vn_valid = 0;
    gac_events(s, s->t, s->x, s->ev);
    return s->fail ? s->fail : 1;
}

/* 1 if at x a persistent contact on a wall with friction slides slower than GAC_SLOW_SLIDING friction_velocity
 * (its velocity along the wall, as in gac_constrained_dynamics_friction): the regularised friction force is then
 * (nearly) viscous, -mu lambda v_t / friction_velocity, a stiff term that bounds an explicit method's step. */
static int gac_slow_sliding(const gac_sim *s, const double *x)
{
    const gac_model *md = s->model;
    const double slow = GAC_SLOW_SLIDING * md->friction_velocity;
    double vq[3 * GAC_AT_LEAST_1(md->npoint)];
    int a, j;
    if (s->nactive == 0 || !gac_has_friction(md)) return 0;
    md->contact_velocities(x, x + md->nq, s->p, vq);
    for (a = 0; a < s->nactive; ++a) {
        const gac_contact *k = &md->contacts[s->active[a]];
        const double mu = k->mu_index >= 0 ? s->p[k->mu_index] : k->mu_value;
        double speed2 = 0.0;
        int axis = 0;
        if (k->kind != GAC_CONTACT_WALL || !k->has_friction || !(mu > 0.0)) continue;
        for (j = 0; j < 2; ++j, ++axis) {             /* the two tangential axes, ascending */
            if (axis == k->axis) ++axis;
            if (k->trow[j] >= 0) speed2 += vq[3 * (k->point - 1) + axis] * vq[3 * (k->point - 1) + axis];
        }
        if (speed2 < slow * slow) return 1;
    }
    return 0;
}

/* Write the samples t_eval[*i_eval ..] that fall in (t_a, t_b] (state from the dense output). */
static void gac_emit(gac_sim *s, double t_b, const double *t_eval, int n_eval, int *i_eval,
                     double *x_eval)
{
    const gac_model *md = s->model;
    while (n_eval > 0 && *i_eval < n_eval && t_eval[*i_eval] <= t_b) {
        double *out = x_eval + (long)(*i_eval) * md->nx;
        if (t_eval[*i_eval] > s->t0_step) {
            gac_dense(s, t_eval[*i_eval], out);
        } else {
            int i;
            for (i = 0; i < md->nx; ++i) out[i] = s->x[i];
        }
        ++*i_eval;
    }
}

int gac_sim_advance(gac_sim *s, double t_end, const double *t_eval, int n_eval, int *i_eval,
                    double *x_eval, gac_impact_record *record)
{
    const gac_model *md;
    long steps = 0;
    double fac_max = 10.0;
    int i;
    if (s == 0 || record == 0 || (n_eval > 0 && (t_eval == 0 || x_eval == 0 || i_eval == 0)))
        return GAC_ERR_NULL_ARGUMENT;
    md = s->model;
    if (!(t_end >= s->t) || !(t_end - t_end == 0.0) || n_eval < 0
        || (n_eval > 0 && (*i_eval < 0 || *i_eval > n_eval)))
        return GAC_ERR_BAD_OPTION;                /* t_end NaN, infinite or before t; bad sample index */
    if (s->pending) {                                        /* the activations of gac_sim_init */
        s->pending = 0;
        record->t = s->t;
        record->ncontact = 0;
        record->complementarity = 0;
        record->energy_before = record->energy_after = gac_total_energy(md, s->x, s->p);
        for (i = 0; i < md->nq; ++i) {
            record->q[i] = s->x[i];
            record->qd_before[i] = record->qd_after[i] = s->x[md->nq + i];
        }
        record->approach_before = record->approach_after = 0.0;
        record->nactivated = s->nactive;
        record->nreleased = 0;
        for (i = 0; i < s->nactive; ++i) record->activated[i] = s->active[i];
        return GAC_SIM_CONTACT;
    }
    if (s->input_changed) {
        const int code = gac_recheck_rest(s, record);
        if (code != 0) return code < 0 ? code : GAC_SIM_CONTACT;
    }
    while (s->t < t_end) {
        double h, t1, t_event = 0.0, err = 0.0;
        int c_event = -1, last;
        if (!s->f_valid) {
            gac_f(s, s->t, s->x, s->f);
            s->f_valid = 1;
        }
        if (s->fail) return s->fail;
        if (s->opt.max_steps > 0 && steps >= s->opt.max_steps) return GAC_ERR_MAX_STEPS;
        if (s->opt.method != GAC_METHOD_RK4 && !(s->h > 0.0)) s->h = gac_initial_step(s, t_end);
        h = s->h;
        if (s->opt.h_max > 0.0 && h > s->opt.h_max) h = s->opt.h_max;
        last = s->t + h >= t_end * (1.0 - 4.0 * GAC_EPS) - 4.0 * GAC_EPS * fabs(t_end);
        if (last) h = t_end - s->t;
        if (!(h > 8.0 * GAC_EPS * fabs(s->t))) {
            if (last) { s->t = t_end; break; }
            return s->fail_seen ? s->fail_seen : GAC_ERR_STEP_SIZE;
        }
        if (s->opt.method == GAC_METHOD_RK4) {
            /* RK4 has no error control: 3 steps in a row at h rho > 2.5, or one far past it, mean the step is
             * beyond its stability */
            const double h_rho = gac_rk4_step(s, h);
            s->n_unstable = h_rho > 2.5 ? s->n_unstable + 1 : 0;
            if (s->n_unstable >= 3 || !(h_rho < 10.0)) return GAC_ERR_UNSTABLE;
        } else {
            double fac;
            const int eighth = s->opt.method == GAC_METHOD_DOP853;
            err = eighth ? gac_dop853_step(s, h) : gac_dopri5_step(s, h);
            if (s->fail == GAC_ERR_BAD_INPUT) return s->fail;
            if (s->fail) {                  /* a trial stage the constraints cannot hold: reject and shrink */
                s->fail_seen = s->fail;
                s->fail = 0;
                err = 1e10;
            }
            if (!(err == err)) err = 1e10;                   /* NaN: reject and shrink */
            fac = err > 0.0 ? 0.9 * pow(err, eighth ? -0.125 : -0.2) : fac_max;
            if (fac > fac_max) fac = fac_max;
            if (fac < 0.2) fac = 0.2;
            if (err > 1.0) {                                 /* reject */
                s->n_rejected++;
                s->h = h * fac;
                fac_max = 1.0;
                steps++;
                continue;
            }
            s->h = h * fac;
            fac_max = 10.0;
            s->fail_seen = 0;
        }
        steps++;
        s->n_steps++;
        if (gac_slow_sliding(s, s->x)) {
            s->n_slow_sliding++;
            s->t_slow_sliding += h;
        }
        if (s->fail) return s->fail;
        if (!gac_finite(s->x1, md->nx)) return GAC_ERR_NONFINITE;
        if (gac_chart_measure(md, s->x1) < gac_chart_floor(s)) return GAC_ERR_GIMBAL_LOCK;
        t1 = last ? t_end : s->t + h;
        gac_prepare_dense(s, h);
        if (gac_find_event(s, t1, &t_event, &c_event)) {
            int code, released = s->is_active[c_event];
            if (s->fail) return s->fail;
            gac_add_work(s, t_event);
            gac_emit(s, t_event, t_eval, n_eval, i_eval, x_eval);
            gac_dense(s, t_event, s->xs);
            code = released ? gac_release(s, t_event, c_event, record)
                            : gac_resolve(s, t_event, c_event, record);
            if (code < 0) return code;
            for (i = 0; i < md->nx; ++i) s->x[i] = code == 1 ? s->x1[i] : s->xs[i];
            s->t = t_event;
            s->f_valid = s->vn_valid = 0;
            gac_events(s, s->t, s->x, s->ev);
            if (s->fail) return s->fail;
            if (released) {                       /* a wall crossing counts once the gap has opened again */
                for (i = 0; i < record->nreleased; ++i) {
                    if (s->ev[record->released[i]] > 0.0) s->ev[record->released[i]] = 0.0;
                }
            }
            if (s->opt.method == GAC_METHOD_RK4) s->h = s->opt.dt;
            if (released) return GAC_SIM_CONTACT;
            if (code == 1) {
                s->n_impacts++;
                return GAC_SIM_IMPACT;
            }
            continue;                                         /* grazing: carry on from the touch */
        }
        gac_add_work(s, t1);
        if (s->fail) return s->fail;
        gac_emit(s, t1, t_eval, n_eval, i_eval, x_eval);
        gac_copy(s->x, s->x1, md->nx);
        {
            const double *f_end = s->opt.method == GAC_METHOD_RK4 ? s->k[4]
                                : s->opt.method == GAC_METHOD_DOP853 ? s->k[12] : s->k[6];
            gac_copy(s->f, f_end, md->nx);
        }
        gac_copy(s->ev, s->eprev, md->ncontact);
        s->t = t1;
        if (s->nactive > 0) {                     /* back onto the persistent constraints */
            int code = gac_project(s, s->x, s->nactive, s->active, 1);
            if (code != GAC_OK) return code;
            s->f_valid = s->vn_valid = 0;
            gac_events(s, s->t, s->x, s->ev);
            if (s->fail) return s->fail;
        }
    }
    while (n_eval > 0 && *i_eval < n_eval && t_eval[*i_eval] <= t_end) {   /* samples at t_end itself */
        for (i = 0; i < md->nx; ++i) x_eval[(long)(*i_eval) * md->nx + i] = s->x[i];
        ++*i_eval;
    }
    return GAC_SIM_END;
}

int gac_sim_run(gac_sim *s, double t_end, long max_impacts, gac_impact_record *record, gac_run_summary *summary)
{
    int code;
    if (s == 0 || record == 0 || summary == 0) return GAC_ERR_NULL_ARGUMENT;
    if (max_impacts < 1) return GAC_ERR_BAD_OPTION;
    summary->n_impacts = summary->n_contact_events = 0;
    summary->t_first_impact = -1.0;
    summary->energy_impact_loss = 0.0;
    for (;;) {
        code = gac_sim_advance(s, t_end, 0, 0, 0, 0, record);
        if (code == GAC_SIM_CONTACT) {
            summary->n_contact_events++;
            continue;
        }
        if (code != GAC_SIM_IMPACT) return code;
        if (summary->n_impacts == 0) summary->t_first_impact = record->t;
        summary->n_impacts++;
        summary->energy_impact_loss += record->energy_before - record->energy_after;
        if (summary->n_impacts >= max_impacts) return GAC_SIM_IMPACT;
    }
}
