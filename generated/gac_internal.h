/*
 * gac_internal.h -- functions shared between the library's source files (not part of the API).
 */
#ifndef GAC_INTERNAL_H
#define GAC_INTERNAL_H

#include "gac.h"

#include <string.h>

#define GAC_EPS 2.220446049250313e-16

/* Contacts one complementarity solve takes: min(nq, GAC_LCP_CAP). */
#define GAC_MAX_LCP(m) ((m)->nq < GAC_LCP_CAP ? (m)->nq : GAC_LCP_CAP)

/* The impact work array (gac_impact_nwork doubles): Y (nq*nq; row a = I_f^-1 n_a of contact a of the set) |
 * A (nq*nq; N I_f^-1 N^T, ncontact_set x ncontact_set, row-major) | g (nq) | vel (3 npoint) | f (max(njrow, 1)). */
#define GAC_WORK_Y(m, w)   (w)
#define GAC_WORK_A(m, w)   ((w) + (long)(m)->nq * (m)->nq)
#define GAC_WORK_G(m, w)   ((w) + 2L * (m)->nq * (m)->nq)
#define GAC_WORK_VEL(m, w) (GAC_WORK_G(m, w) + (m)->nq)
#define GAC_WORK_F(m, w)   (GAC_WORK_VEL(m, w) + 3L * (m)->npoint)
/* and for a model with friction: Z (nq*nq; row a = I_f^-1 J_t^T phi_a, the response to contact a's unit friction
 * force) | B (nq*nq; the normal rows applied to the normal and friction directions, ncontact_set x ncontact_set). */
#define GAC_WORK_Z(m, w)   (GAC_WORK_F(m, w) + GAC_AT_LEAST_1((m)->njrow))
#define GAC_WORK_B(m, w)   (GAC_WORK_Z(m, w) + (long)(m)->nq * (m)->nq)
/* and W (9 nq*nq): the contact-space inverse inertia of a frictional impact's normal and tangential directions
 * (Z and B then hold those directions' responses I_f^-1 d, up to 2 nq rows). */
#define GAC_WORK_W(m, w)   (GAC_WORK_B(m, w) + (long)(m)->nq * (m)->nq)
/* and T (2 nq*nq: the responses I_f^-1 J^T e_r to stuck points' tangential rows r) | L (9 nq*nq: the factor of the
 * held rows' system, gac_stick.c; W then holds that system, up to 3 nq square). */
#define GAC_WORK_T(m, w)   (GAC_WORK_W(m, w) + 9L * (m)->nq * (m)->nq)
#define GAC_WORK_L(m, w)   (GAC_WORK_T(m, w) + 2L * (m)->nq * (m)->nq)

#define GAC_V_FLOOR 1e-12   /* m/s: a contact at its wall approaching slower than this, or than 1e-10 of
                               the fastest contact's normal speed (gac_v_round), is at rest: round-off */

/* dst[0..n-1] = src[0..n-1] (distinct arrays). */
static inline void gac_copy(double *dst, const double *src, int n)
{
    if (n > 0) memcpy(dst, src, (size_t)n * sizeof *dst);
}

/* 1 if x[0..n-1] are all finite. */
static inline int gac_finite(const double *x, int n)
{
    int i;
    for (i = 0; i < n; ++i) {
        if (!(x[i] - x[i] == 0.0)) return 0;
    }
    return 1;
}

/* gac_sim.c: the right-hand side and event functions of the loop */
const double *gac_input(gac_sim *s, double t, const double *x);
void gac_f(gac_sim *s, double t, const double *x, double *f);
void gac_f_end(gac_sim *s, double t, const double *x, double *f);
void gac_events(gac_sim *s, double t, const double *x, double *ev);

/* gac_integrate.c: the integrators and their dense output */
double gac_initial_step(gac_sim *s, double t_end);
double gac_rk4_step(gac_sim *s, double h);
double gac_dopri5_step(gac_sim *s, double h);
double gac_dop853_step(gac_sim *s, double h);
void gac_prepare_dense(gac_sim *s, double h);
void gac_dense(gac_sim *s, double t, double *out);
int gac_tableau(int method, const double **a, int *lda, const double **b, const double **c);

/* gac_sens.c: the sensitivities carried along a run (sim->sens) */
void gac_sens_flight(gac_sim *s, const double *x, double h, int taken); /* S over [t, t + h] from x at s->t */
void gac_sens_sample(gac_sim *s, double t, double *out);  /* S at a sample time within the step */
void gac_sens_impact(gac_sim *s, const gac_impact_record *r, int c_event,
                     const int *was_stuck);     /* the jump at an impact just resolved (was_stuck: before it) */
void gac_sens_stop(gac_sim *s, int status, double t, int contact);    /* an event not differentiated */
void gac_sens_rest_set(gac_sim *s, double t);   /* the resting set changed: a held link or obstacle not followed
                                                   (rough, or its normal without a derivative) ends them */
void gac_sens_project(gac_sim *s, const double *x_pre, const double *x_post); /* a step's projection onto the rest */
void gac_sens_release(gac_sim *s, const gac_impact_record *r, int c_event);  /* the release of a resting contact */
void gac_sens_slip(gac_sim *s, const gac_impact_record *r, int c_event);   /* a stuck point's slip at its event */
void gac_sens_stick(gac_sim *s, const double *x_before, const int *stuck_before, const double *slip_before,
                    const gac_impact_record *r);   /* points that stuck at a step's end */
void gac_sens_reslip(gac_sim *s, const double *slip_before, int nstuck);   /* slip directions a stick test gave */
void gac_sens_fixed_release(gac_sim *s);   /* released or slipped where the inputs change: dt = 0, S goes on */
/* a switch of the bases of flip (bit j for base j): x on `from` became y on `to`, S carried through the
   conversion's derivative */
void gac_sens_switch(gac_sim *s, const gac_model *from, const gac_model *to, int flip, const double *x,
                     const double *y);
/* S at x (the chart integrated now) into chart A's coordinates at xa (x converted), in place */
void gac_sens_to_chart_a(const gac_sim *s, const double *x, const double *xa, double *S);

/* gac_events.c: event location and the loop's tolerances */
double gac_v_round(const gac_model *md, const double *vn);
/* 1 if contact c is redundant at gaps[] (gac_redundant_depth below the tie 1e-6 contact_tol + 1e-15): not an
 * impact's contact, not held; and the lift its event value takes so that it locates no crossing while its joint
 * point's contact does, held at a gap down to -contact_tol: 2 (contact_tol + tie) (1 - max(depth, 0) / tie) below the
 * tie, 0 above it (the link nearest inside by more than the tie: its crossing is located where it goes under). */
int gac_redundant(const gac_sim *s, int c, const double *gaps, const double *geometry);
double gac_redundant_lift(const gac_sim *s, int c, const double *gaps, const double *geometry);
/* Every contact's gap at state x, each redundant one lifted (gac_redundant_lift): the event values of the contacts
 * that are not resting (gac_events). */
void gac_event_gaps(const gac_sim *s, const double *x, double *gaps);
double gac_extent(const gac_sim *s, const double *x);
double gac_graze_depth(const gac_sim *s, const double *x);
int gac_find_event(gac_sim *s, double t1, double *t_event, int *c_event);
double gac_chart_floor(const gac_sim *s);
double gac_simultaneity_window(const gac_sim *s, const double *x);
void gac_note_lost(gac_sim *s, int c, double t, double gap, double depth);

/* gac_rest.c: resting contact */
double gac_total_energy(const gac_model *md, const double *x, const double *p);
void gac_normal_velocities(const gac_model *md, const double *x, const double *p, double *vn);
int gac_holdable(const gac_sim *s, const double *x, int c);   /* 1 if contact c can be held at its wall */
int gac_normal_accelerations(gac_sim *s, double t, const double *x, int n, const int *set, double *an);
int gac_add_independent(gac_sim *s, const double *x, int *n, int *set, int c);
int gac_project(gac_sim *s, double *x, int n, const int *set, int positions);
int gac_settle(gac_sim *s, double t, const double *x, int *n, int *set);
int gac_hold(gac_sim *s, double *x, int nset, const int *set, int n, const int *list);
void gac_set_resting(gac_sim *s, int n, const int *set, gac_impact_record *r);
int gac_rest_at_start(gac_sim *s);
int gac_release(gac_sim *s, double t, int c_event, gac_impact_record *r);
void gac_contact_record(const gac_sim *s, double t, const double *x, gac_impact_record *r);
int gac_recheck_rest(gac_sim *s, gac_impact_record *record);

/* gac_energy.c: the energy balance */
double gac_energy_tolerance(const gac_options *opt);
void gac_energy_start(gac_sim *s);
int gac_energy_check(gac_sim *s, const double *E_known);   /* E_known: T, V at s->x if evaluated, or NULL */
int gac_energy_projected(gac_sim *s, double E_before, const double *x);
double gac_step_energy_error(gac_sim *s);

/* gac_resolve.c: one impact event */
int gac_impact_inaccurate(const gac_sim *s, double b);
int gac_resolve(gac_sim *s, double t, int c_event, gac_impact_record *r);

/* gac_model.c */
int gac_has_friction(const gac_model *m);

/* gac_obstacle.c: boxes and planes as fixed obstacles.  The kind of obstacle o (GAC_OBSTACLE_*); whether a kind is
 * a capsule about a segment (a bar or a sphere: gac_link.c's distance); how many runtime parameters a kind's geometry
 * takes (0: not a kind); for a box's or a plane's shape row (gac_obstacle_shape), the contact geometry
 * (GAC_LINK_NGEOMETRY doubles, as gac_obstacle_gap's, t = 0) of segment a0-a1 of radius `radius`, returning 1 (0: a
 * capsule's row, nothing written); GAC_OK if obstacle o's constant shape is well formed and its parameters' place
 * fits p (else GAC_ERR_BAD_MODEL). */
int gac_obstacle_kind(const gac_model *m, int o);
int gac_obstacle_round(int kind);
int gac_obstacle_nparam(int kind);
int gac_obstacle_shape_contact(const double *shape, const double *a0, const double *a1, double radius,
                               double *geometry);
int gac_obstacle_shape_check(const gac_model *m, int o);
/* The part of a box's or plane's shape row that segment a0-a1's gap is measured from (gac_obstacle_shape_contact):
 * 0 a face (the plane's, or a box's that the link's closest point is over or reaches in through: a constant
 * normal), 1 a box's edge (the link's closest point by it outside, or the link reaching in across it), its ends in
 * b0, b1, 2 a box's corner, b0 = b1 (the normal then turns with the link, as against a segment's capsule) */
int gac_obstacle_feature(const double *shape, const double *a0, const double *a1, double *b0, double *b1);
/* The motion of that part along the change dshape of the obstacle's geometry (its position and size; a box's
 * rotation held, gac_obstacle_turn_admissible; a plane's normal's turn enters its gap and row in gac_link.c): an
 * edge's or a corner's ends b0, b1, each
 * coordinate of them in the box's frame +-h_k, move by dc + R dy, dy_k = +-dh_k; a box's face (n its outward normal,
 * R^T n = +-E_k) by dc + dh_k n, a plane's by its point's motion, into db0 = db1.  Returns the part as
 * gac_obstacle_feature. */
int gac_obstacle_feature_change(const double *shape, const double *dshape, const double *a0, const double *a1,
                                const double *n, double *db0, double *db1);
/* Obstacle o's geometry's change along dp (GAC_OBSTACLE_NSHAPE doubles, the kind first as gac_obstacle_shape's, the
 * rest the entries' changes; 0 for an obstacle whose geometry is the model's constants).  GAC_OK or as
 * gac_obstacle_shape. */
int gac_obstacle_shape_change(const gac_model *m, const double *dp, int o, double *dshape);
/* 1 if the change dp (nparam) moves obstacle o only along directions the sensitivities take: none of a box's rotation
 * entries (a rotation's tangent is not followed), a plane's normal only turned, n . dn = 0 (to 1e-12 |dn|), about its
 * point; else 0. */
int gac_obstacle_turn_admissible(const gac_model *m, const double *p, const double *dp, int o);

/* gac_link.c: link pairs and obstacles as contacts of the loop (kinds GAC_CONTACT_LINK, GAC_CONTACT_OBSTACLE, the
 * last entries of m->contacts: no Jacobian row; Coulomb friction along their contact frame, at impacts and at rest,
 * where they are held by g = J^T n and its bias, and, stuck, by J^T t1, J^T t2 and theirs) */
int gac_rowless(const gac_model *m, int c);             /* 1 if contact c is a link pair or an obstacle */
/* The first held link pair or link on a bar of set[0..n-1] whose other end came closer than its held point by more
 * than tol over the step x0 -> x1 (a line contact its one point cannot hold), else -1 (gac_link.c). */
/* A link's contact with a box beside its joint points' (gac_contact.end), or a link pair's beside its end contacts
 * (either link's joint points against the other): how far its gap (gaps[c], the least over the link or the pair)
 * lies below the least of those (partner: gac_redundant_partners), gaps[] every contact's and geometry[] the
 * rowless contacts' (from gac_contact_gaps_geometry); +inf for any other contact.  Where that is ~0 the link is nearest at an end (or along a stretch reaching one), which the joint
 * point's contact measures as well: the link's contact is then redundant (gac_redundant, gac_events.c).  An end's
 * contact against a link whose nearest point is that link's own end is redundant too (-inf): that end's contact
 * against the first link is no farther (two links meeting end to end are one contact, not two). */
double gac_redundant_depth(const gac_model *m, const int *partner, int c, const double *gaps, const double *geometry);
/* The contacts each contact's redundancy is read from (gac_redundant_depth), GAC_PARTNERS per contact (-1: none),
 * found once per run (gac_sim_bind, into the sim's iwork): a link's or a pair's contact: its ends' contacts; a
 * pair's end contact: [0], [1] the other link's start's and end's contacts against a link ending at its point. */
#define GAC_PARTNERS 4
void gac_redundant_partners(const gac_model *m, int *partner);
/* gac_contact_gaps, and each link pair's and obstacle contact's geometry (GAC_LINK_NGEOMETRY doubles each, from the
 * first contact after the kernel's: gac_contact_geometry's) from one evaluation of the joint points. */
void gac_contact_gaps_geometry(const gac_model *m, const double *q, const double *p, double *gaps, double *geometry);
int gac_line_contact(const gac_model *m, const double *x0, const double *x1, const double *p, int n, const int *set,
                     double tol);
int gac_kernel_contacts(const gac_model *m);            /* the contacts before them: those of contact_gaps */
int gac_has_link(const gac_model *m, int n, const int *list);   /* 1 if list[0..n-1] holds one of them */
/* every contact's gap (ncontact): the kernel's, then each link pair's and obstacle's (gac_link_gap,
 * gac_obstacle_gap) */
void gac_contact_gaps(const gac_model *m, const double *q, const double *p, double *gaps);
/* 1 if contact c is a link pair or an obstacle of finite extent (a sphere, a bar, a box: not a plane) */
int gac_finite_contact(const gac_model *m, int c);
/* finite contact c's largest point speed relative to the other side at state x (m/s): max over link i's joint
   points of |v|, plus link j's for a link pair */
double gac_finite_speed(const gac_model *m, const double *x, const double *p, int c);
void gac_link_contact_direction(const gac_model *m, const double *q, const double *p, int c, double *g);
/* link or obstacle contact c's gap rate n . (v_P - v_Q) from the joint points' velocities vel (npoint x 3) at q */
double gac_link_contact_rate(const gac_model *m, const double *q, const double *p, int c, const double *vel);
/* every link or obstacle contact's gap rate into vn[c] (from the first after the kernel's), the joint points once */
void gac_link_contact_rates(const gac_model *m, const double *q, const double *p, const double *vel, double *vn);
/* a held link or obstacle contact c's bias dg(qd) . qd (its normal acceleration less g . qdd) into *b: GAC_OK, or
 * GAC_ERR_LINK_CONTACT where its normal has no derivative */
int gac_rowless_bias(const gac_model *m, const double *q, const double *qd, const double *p, int c, double *b);
/* the derivatives of its row biases (rows = 1: the normal's, gac_rowless_bias; rows = 3: the normal's and the frame's
 * t1, t2, gac_rowless_frame_bias) along (dq, dqd, dp) into db (rows): exact along dqd, a fourth-order central
 * difference of them along (dq, dp) (~1e-12 of their size): GAC_OK, or GAC_ERR_LINK_CONTACT where a row has no
 * derivative */
int gac_rowless_bias_tangent(const gac_model *m, const double *q, const double *qd, const double *p, int c, int rows,
                             const double *dq, const double *dqd, const double *dp, double *db);
/* the biases b (3) of a held link or obstacle contact c's frame rows J^T n, J^T t1, J^T t2 (b[0] gac_rowless_bias's):
 * GAC_OK, or GAC_ERR_LINK_CONTACT where its frame has no derivative */
int gac_rowless_frame_bias(const gac_model *m, const double *q, const double *qd, const double *p, int c, double *b);
void gac_link_refine(const gac_model *m, const double *q, const double *p, int n, const int *list, double *F,
                     const double *qd, double *qd_plus, double *work);
double gac_link_law_accuracy(const gac_model *m, const double *q, const double *p, int n, const int *list,
                             const double *F, const double *Ft, const double *qd, const double *qd_plus, double T);
/* A link pair's or an obstacle's contact frame at q (gac_rowless_frame): its links i and j (0: a fixed obstacle),
 * the closest points' fractions s, t along them, and the rows n, t1, t2 of axis (a right-handed orthonormal basis,
 * n the inward normal, t1 link i's axis off n).  The frictional impact law's rows of such a contact are J^T n,
 * J^T t1, J^T t2 (gac_frame_direction), its velocities the closest points' relative velocity along them
 * (gac_frame_rate). */
typedef struct {
    int i, j;
    double s, t;
    double axis[3][3];
} gac_contact_frame;
int gac_rowless_frame(const gac_model *m, const double *q, const double *p, int c, gac_contact_frame *f);
double gac_frame_rate(const gac_contact_frame *f, const double *vel, int k, double *size);
double gac_frame_direction(const gac_model *m, const double *q, const double *p, const gac_contact_frame *f, int k,
                           double *g);

/* gac_linalg.c */
int gac_lu_solve(int n, double *A, double *b, double tol);
double gac_dot(int n, const double *a, const double *b);   /* sum a_i b_i, i < n */
int gac_ldlt(int n, double *A, double tol);
void gac_ldlt_solve(int n, const double *LD, double *b);
int gac_ldlt_ld(int n, long double *A, double tol);
void gac_ldlt_ld_solve(int n, const long double *LD, long double *b);
int gac_ldlt_drop(int n, double *A, double tol);

/* gac_impact.c */
void gac_contact_row(const gac_model *m, int c, int *row, double *sign);
double gac_row_value(const gac_model *m, int c, const double *w, const double *vel);
void gac_contact_direction(const gac_model *m, const double *q, const double *p, int c, double *f, double *g);
double gac_normal_value(const gac_model *m, const double *q, const double *p, int c, const double *w,
                        const double *vel);
int gac_normal_bias(const gac_model *m, const double *q, const double *qd, const double *p, int c, const double *bias,
                    double *b);
double gac_restitution(const gac_model *m, const double *p, int c);
int gac_row_response(const gac_model *m, const double *q, const double *p, int row, double *f, double *g,
                     double *out);
int gac_impact_system(const gac_model *m, const double *q, const double *qd, const double *p, int ncontact_set,
                      const int *contact_set, double *work, double *v, double *e);
int gac_friction_consistent(int n, const double *B, double tol);
int gac_constrained_dynamics_friction(const gac_model *m, const double *q, const double *qd, const double *u,
                                      const double *p, int nresting, const int *resting, const int *stuck,
                                      const double *slip, double *qdd, double *lambda, double *lambda_t, double *work,
                                      double *dissipation);
int gac_impact_rounds(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                      const int *list, const double *e, int first, double *qd_plus, double *F, double *work,
                      int *rounds, int *plastic);
/* What gac_impact_rounds_traced records of each round (for the sensitivities' differential of the rounds): the
 * contacts of round j's complementarity problem, k[j] of them, at positions idx[j n + i] of the law's list, hit[j n +
 * i] = 1 where struck with its own e (approaching; 0: at rest in that round, or the plastic round), F[j n + i] their
 * impulses in that round.  The caller's arrays, room for cap rounds (nround > cap: more rounds than recorded).
 * gac_impact_rounds_friction_traced records the same and, per contact i of round j, its rows dim[j n + i] (its normal,
 * then its tangential axes') and their impulses L[j 3n + 3i + r] (F then holds the normal ones). */
typedef struct {
    int cap, n, nround;
    int *k, *idx, *hit;
    double *F;
    int *dim;
    double *L;
} gac_rounds_trace;
int gac_impact_rounds_traced(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                             const int *list, const double *e, int first, double *qd_plus, double *F, double *work,
                             int *rounds, int *plastic, gac_rounds_trace *trace);
int gac_impact_rounds_work(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                           const int *list, const double *e, int first, double *qd_plus, double *F, double *work,
                           int *rounds, int *plastic, double *rest_work, double *law_change);


/* gac_impact_accuracy.c: the impact's accuracy, measured after its law, and iterative refinement */
/* gac_resolve.c: a wall's impulse left below zero by round-off (<= 1e-12 of the largest) taken out with its velocities */
void gac_drop_roundoff_pulls(const gac_model *md, const double *x, const double *p, int n, const int *list, double T,
                             double *F, double *Ft, double *qd_plus);
/* gac_impact_accuracy.c: the momentum balance against a generalized impulse g, in long double with its measured
 * evaluation floor (0: the model has no long-double kernels) */
int gac_momentum_balance_ld(const gac_model *m, const double *q, const double *p, const long double *g,
                            const double *qd, const double *qd_plus, double *balance, double *floor);
void gac_refine_response(const gac_model *m, const double *q, const double *p, const double *g, double *y,
                         double *r, double *dy);
int gac_impact_system_refined(const gac_model *m, const double *q, const double *qd, const double *p,
                              int ncontact_set, const int *contact_set, double *work, double *v, double *e);
double gac_refine_impulses(const gac_model *m, const double *q, const double *p, int n, const int *list,
                           const double *e, int rounds, double *F, const double *qd, double *qd_plus, double *work,
                           double *targets);
int gac_rounds_velocities(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                          const int *list, const double *F, int rounds, double *work, double *v);
void gac_close_approach(const gac_model *m, const double *q, const double *p, int n, const int *list,
                        double *F, const double *qd, double *qd_plus, double v_tol, double *work);
double gac_frictionless_law_work(const gac_model *m, const double *q, const double *p, int n, const int *list,
                                 const double *e, const double *F, int rounds, int plastic, const double *targets,
                                 double rest_work, const double *qd, const double *qd_plus);
double gac_impact_accuracy(const gac_model *m, const double *q, const double *p, int n, const int *list,
                           const double *e, double *F, double *Ft, int law, int rounds, int plastic,
                           const double *qd, double *qd_plus, double T, double *work, double *v_acc,
                           const double *targets, double rest_work, int *part);

/* gac_impact_friction.c */
double gac_friction_coefficient(const gac_model *m, const double *p, int c);
double gac_contact_friction(const gac_model *m, const double *p, int c);
int gac_impact_rounds_friction(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                               const int *list, const double *e, int first, int law, double *qd_plus, double *F,
                               double *Ft, double *work, int *rounds, int *plastic, int *law_used, double *residual,
                               double *tangential_parts);
int gac_impact_rounds_friction_traced(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                                      const int *list, const double *e, int first, int law, double *qd_plus,
                                      double *F, double *Ft, double *work, int *rounds, int *plastic, int *law_used,
                                      double *residual, double *tangential_parts, gac_rounds_trace *trace);
/* The tangential impact at the contacts list[0..n-1] (n <= 6), resting at their walls (normal velocities 0) with some
 * sliding where their sliding system is no P-matrix: the frictional impact law (GDI, e = 0 at a contact at rest) on
 * their normal and tangential rows, its non-trivial solution (some L_N > 0; the first of the contacts' modes from all
 * stuck on).  qd_plus (nq), F (n), Ft (2 n) as gac_impact_rounds_friction, *residual the law's largest relative
 * violation (an impulse at the cone's edge, the jam, put onto it).  GAC_ERR_FRICTION when no non-trivial solution
 * meets the law to GAC_FRICTION_RESIDUAL_MAX. */
int gac_impact_tangential(const gac_model *m, const double *q, const double *qd, const double *p, int n,
                          const int *list, double *qd_plus, double *F, double *Ft, double *work, double *residual,
                          double *tangential_parts);
/* Where that has none: the impulses in the contacts' Coulomb cones (n <= GAC_JAM_CONTACTS) that take the most
 * kinetic energy (the maximal-dissipation impact, a convex problem; its optimum leaves no contact approaching),
 * qd_plus, F, Ft as gac_impact_tangential.  GAC_ERR_FRICTION where the least energy change is not negative. */
#define GAC_JAM_CONTACTS 10
int gac_impact_cones(const gac_model *m, const double *q, const double *qd, const double *p, int n, const int *list,
                     double *qd_plus, double *F, double *Ft, double *work);

/* gac_setup.c */
double gac_clock_now(const gac_sim *s);          /* the run's clock (s): the embedder's, or C's processor time */
void gac_schedule_begin(gac_sim *s);             /* the schedule's interval that holds s->t begins: its inputs */

/* gac_chart.c: a model's bases, one or several (gac_model.nbase) */
int gac_nbase(const gac_model *m);                          /* its bases (1 unless nbase says more) */
const gac_base *gac_model_base(const gac_model *m, int j);   /* base j */
const gac_chart *gac_model_chart(const gac_model *m, int j); /* base j's measure */
const gac_model *gac_chart_model(const gac_model *a, int chart); /* the model of sim.chart `chart` (NULL: none) */
double gac_chart_measure_of(const gac_chart *c, const double *q); /* one base's measure at q */

/* gac_switch.c: the base charts in the loop (masks: bit j for base j) */
int gac_can_switch(const gac_sim *s);            /* 1 if the run may switch charts (option on, second chart) */
int gac_wants_switch(const gac_sim *s);          /* the bases that should leave the chart they are on, at s->x */
int gac_step_near_lock(const gac_sim *s);        /* the bases whose step s->x -> s->x1 ends below the floor or
                                                    passes the lock */
int gac_switch_chart(gac_sim *s, int flip);      /* continue with the bases of flip on their other chart from s->x */
int gac_state_chart_a(const gac_sim *s, const double *x, double *out);   /* x in chart A's coordinates */
int gac_tangent_between(const gac_model *from, const gac_model *to, int mask, const double *x, const double *y, int k,
                        double *S);              /* S at x on `from` carried to y on `to`, the bases of mask */
void gac_to_chart_a(gac_sim *s, double *x);      /* a state of the chart integrated now, in chart A's coordinates
                                                    (a conversion that fails is kept in s->fail) */
int gac_report(gac_sim *s, gac_impact_record *record, int code);   /* the record in chart A's coordinates */

/* gac_jam.c: the tangential impact where sliding resting contacts have no consistent forces (Painleve) */
int gac_jam(gac_sim *s, gac_impact_record *r);   /* at s->x: GAC_SIM_IMPACT (record reported) or an error */

/* gac_stick.c: stuck and sliding points at rough resting contacts.  A resting contact's two tangential directions
 * (gac_tangents): a wall's, its point's velocity along the box axes other than its normal (the Jacobian rows trow,
 * velocity components comp; has[j] 0 for an axis without a row); a link pair's or an obstacle's, the closest points'
 * relative velocity along its frame's t1, t2 (gac_rowless_frame; rows J^T t1, J^T t2, their biases from
 * gac_rowless_frame_bias). */
typedef struct {
    int c, rowless, has[2], comp[2];
    gac_contact_frame frame;
} gac_tangents;
double gac_rest_friction(const gac_model *m, const double *p, int c);   /* c's Coulomb coefficient at rest */
int gac_tangents_at(const gac_model *m, const double *q, const double *p, int c, gac_tangents *tg);
double gac_tangent_value(const gac_tangents *tg, int j, const double *vel);
void gac_tangent_force(const gac_model *m, const double *q, const double *p, const gac_tangents *tg,
                       const double *phi, double *f, double *g);
double gac_slide_phi(const double *vt, double vs, const double *d, double *phi);
void gac_tangential_velocity(const gac_model *m, const double *q, const double *p, int c, const double *vq,
                             double *vt);
int gac_any_stuck(const int *stuck, int n, const int *set);
int gac_stuck_dynamics(const gac_model *m, const double *q, const double *qd, const double *u, const double *p,
                       int n, const int *set, const int *stuck, const double *slip, double *qdd, double *lambda,
                       double *lambda_t, double *work, double *dissipation);
int gac_project_stuck(gac_sim *s, double *x, int n, const int *set);
int gac_rest_forces(gac_sim *s, double t, const double *x, double *qdd, double *lambda, double *lambda_t,
                    double *dissipation);
int gac_slip(gac_sim *s, double t, const double *x, int c, gac_impact_record *r);
void gac_tangential_speeds(const gac_sim *s, const double *x, double *vt);
int gac_try_stick(gac_sim *s, const double *vt_start, int count_loss, const int *was_stuck, gac_impact_record *r);
int gac_restick(gac_sim *s, int count_loss, const int *was_stuck, gac_impact_record *r);

/* gac_energy.c: work and sliding */
void gac_add_work(gac_sim *s, double t_b);       /* the work of inputs, dampers and friction over [s->t, t_b] */
int gac_slow_sliding(const gac_sim *s, const double *x);   /* 1 if a resting point slides in the viscous regime */

#endif /* GAC_INTERNAL_H */
