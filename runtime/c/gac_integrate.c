/*
 * gac_integrate.c -- the flight integrators: RK4 (fixed step), Dormand-Prince 5(4) and 8(5,3) with error control
 * (Hairer, Norsett & Wanner, Solving ODEs I), one step each from s->x0 to s->x1, and their dense output on the
 * step just taken (4th-order Hermite-type for DOPRI5, 7th-order for DOP853, cubic Hermite for RK4).
 */
#include "gac_internal.h"

#include <math.h>

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

/* A step's error norm with its energy error (gac_step_energy_error: 0 where the flight is not conservative):
 * the larger of the two, so that the step also keeps the energy to the tolerance. */
static double gac_with_energy(gac_sim *s, double err)
{
    const double e = gac_step_energy_error(s);
    return e > err ? e : err;
}

/* Starting step for DOPRI5 (Hairer, Norsett & Wanner, Solving ODEs I, Sect. II.4). */
double gac_initial_step(gac_sim *s, double t_end)
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
double gac_rk4_step(gac_sim *s, double h)
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
    gac_f_end(s, s->t + h, s->x1, s->k[4]);    /* derivative at the end: Hermite and next step */
    return dy > 0.0 ? h * sqrt(dk / dy) : 0.0;
}

/* One Dormand-Prince 5(4) step of size h; returns the error norm; x1 and k[6] = f(t + h, x1). */
double gac_dopri5_step(gac_sim *s, double h)
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
    gac_f_end(s, t + h, s->x1, k7);
    gac_error6(nq, s->xs, h, e1, k1, e3, k3, e4, k4, e5, k5, e6, k6, e7, k7);   /* the error estimate, in xs */
    return gac_with_energy(s, gac_norm(s, s->xs, s->x, s->x1));
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
double gac_dop853_step(gac_sim *s, double h)
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
    gac_f_end(s, s->t + h, s->x1, K[12]);
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
    if (e5 == 0.0 && e3 == 0.0) return gac_with_energy(s, 0.0);
    return gac_with_energy(s, fabs(h) * e5 / sqrt((e5 + 0.01 * e3) * nx));
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
void gac_prepare_dense(gac_sim *s, double h)
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
void gac_dense(gac_sim *s, double t, double *out)
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

/* The Butcher tableau of the method's solution (its stages up to the last with a nonzero weight): *a (row i's
 * coefficients at a[i*lda .. ], i < stages), *b (stages weights), *c (stages nodes); returns the stages.  The
 * sensitivities (gac_sens.c) take the state's steps with it. */
int gac_tableau(int method, const double **a, int *lda, const double **b, const double **c)
{
    static const double rk4_a[4][4] = {{0.0}, {0.5}, {0.0, 0.5}, {0.0, 0.0, 1.0}};
    static const double rk4_b[4] = {1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0}, rk4_c[4] = {0.0, 0.5, 0.5, 1.0};
    static const double dopri5_a[6][6] = {
        {0.0},
        {1.0 / 5.0},
        {3.0 / 40.0, 9.0 / 40.0},
        {44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0},
        {19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0},
        {9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0}};
    static const double dopri5_b[6] = {35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0,
                                       11.0 / 84.0};
    static const double dopri5_c[6] = {0.0, 0.2, 0.3, 0.8, 8.0 / 9.0, 1.0};
    if (method == GAC_METHOD_RK4) {
        *a = &rk4_a[0][0], *lda = 4, *b = rk4_b, *c = rk4_c;
        return 4;
    }
    if (method == GAC_METHOD_DOP853) {             /* the solution's weights are the row of stage 13 (c = 1) */
        *a = &gac_dop853_a[0][0], *lda = 16, *b = gac_dop853_a[12], *c = gac_dop853_c;
        return 12;
    }
    *a = &dopri5_a[0][0], *lda = 6, *b = dopri5_b, *c = dopri5_c;
    return 6;
}
