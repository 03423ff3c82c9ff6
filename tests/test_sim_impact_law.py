"""The impact law with complementarity (NAME_impact_complementarity, the law the hybrid loop applies)
against an independent numpy model: the reference chain's mass matrix and point Jacobian (not the
generated kernels), each round solved as the Eq. 48 block system [[I_f, -N^T], [N, 0]] for every
candidate set of pushing contacts (not the contact-space matrix N I_f^-1 N^T the C code uses).

The law: in rounds, the contacts that approach (v < 0) or rest (v = 0) take part,
0 <= F _|_ v+ + e v- >= 0 on them; repeated until no contact approaches."""
from itertools import combinations

import numpy as np
import pytest

from studies import reference
from conftest import chain, random_parameters, reference_of


def contact_rows(model, ref, q, contact_set):
    """Rows of the contacts along their inward normals, from the reference model's point Jacobian."""
    Jp = ref.point_jacobian(q)
    return np.array([model.contacts[c][1].normal_sign * Jp[model.contacts[c][0] - 1, model.contacts[c][1].axis]
                     for c in contact_set])


def block_solve(M, N, qd, target):
    """Eq. 48 for the rows N: [[M, -N^T], [N, 0]] [qd+; F] = [M qd; target]."""
    k, nq = len(N), len(qd)
    A = np.block([[M, -N.T], [N, np.zeros((k, k))]])
    x = np.linalg.solve(A, np.r_[M @ qd, target])
    return x[:nq], x[nq:]


def reference_round(M, N, qd, e, struck):
    """One round by brute force: among the sets S of the taking-part contacts, the one whose Eq. 48 solve
    (v+_S = -e_S v-_S for struck contacts, 0 for resting ones) has F_S >= 0 and leaves every other
    taking-part contact at v+ >= -e v- (>= 0 if resting)."""
    v = N @ qd
    part = [a for a in range(len(v)) if struck[a] or abs(v[a]) <= 1e-11 * np.abs(v).max()]
    bound = np.where(struck, -e * v, 0.0)
    scale = np.abs(v).max()
    for size in range(len(part), 0, -1):
        for S in combinations(part, size):
            S = list(S)
            qd_plus, F = block_solve(M, N[S], qd, bound[S])
            if F.min() < -1e-10 * max(np.abs(F).max(), 1e-300):
                continue
            w = N @ qd_plus - bound
            if all(w[a] >= -1e-9 * scale for a in part if a not in S):
                full = np.zeros(len(v))
                full[S] = np.maximum(F, 0.0)
                return qd_plus, full
    return qd.copy(), np.zeros(len(v))


def reference_law(M, N, qd, e):
    F_total = np.zeros(len(N))
    for _ in range(256):
        v = N @ qd
        struck = v < -1e-11 * np.abs(v).max()
        if not struck.any():
            break
        qd, F = reference_round(M, N, qd, e, struck)
        F_total += F
    return qd, F_total


@pytest.mark.parametrize("n,seed", [(1, 3), (2, 5), (3, 7), (4, 11)])
def test_law_matches_the_reference_on_mixed_contact_sets(compiled, n, seed):
    """Random links, sets of contacts that approach or separate, random e in [0, 1] (some exactly 0 and 1):
    the compiled law equals the brute-force rounds of the reference model to 1e-10."""
    scene = chain(n, twists=True)
    model = compiled(scene)
    rng = np.random.default_rng(seed)
    names = scene.parameter_names()
    checked = 0
    for trial in range(25):
        p = random_parameters(scene, seed=100 * seed + trial)
        ref = reference_of(scene, p)
        for i, name in enumerate(names):
            if name.startswith("e_"):
                p[i] = rng.choice([0.0, 1.0, rng.uniform()])
        q, qd = reference.random_state(n, rng)
        k = int(rng.integers(1, min(n + 1, 3) + 1))
        points = rng.choice(np.arange(1, n + 2), size=k, replace=False)
        contact_set = [int(rng.choice([c for c, (pt, w) in enumerate(model.contacts) if pt == point]))
                  for point in points]
        N = contact_rows(model, ref, q, contact_set)
        if np.linalg.matrix_rank(N) < len(contact_set):
            continue
        e = np.array([p[names.index(f"e_{model.contacts[c][1].name}")] for c in contact_set])
        qd_ref, F_ref = reference_law(ref.mass_matrix(q), N, qd, e)
        qd_plus, F = model.impact(q, qd, contact_set, p, mode="complementarity")
        scale = np.abs(qd).max()
        assert np.allclose(qd_plus, qd_ref, rtol=1e-9, atol=1e-10 * scale), (trial, contact_set)
        assert np.allclose(F, F_ref, rtol=1e-8, atol=1e-10 * np.abs(F_ref).max() + 1e-300), (trial, contact_set)
        checked += 1
    assert checked >= 15


def test_post_conditions_on_random_contact_sets(compiled):
    """F >= 0, no contact approaches afterwards, the kinetic energy never grows, and it is kept when every
    wall has e = 1: on 200 random states and sets of 1-4 contacts (approaching, resting or separating),
    measured with the reference model."""
    scene = chain(3, twists=True)
    model = compiled(scene)
    rng = np.random.default_rng(21)
    names = scene.parameter_names()
    for trial in range(200):
        p = random_parameters(scene, seed=2100 + trial)
        ref = reference_of(scene, p)
        elastic = trial % 2 == 0
        for i, name in enumerate(names):
            if name.startswith("e_"):
                p[i] = 1.0 if elastic else rng.uniform()
        q, qd = reference.random_state(3, rng)
        points = rng.choice(np.arange(1, 5), size=int(rng.integers(1, 5)), replace=False)
        contact_set = [int(rng.choice([c for c, (pt, w) in enumerate(model.contacts) if pt == point]))
                  for point in points]
        qd_plus, F = model.impact(q, qd, contact_set, p, mode="complementarity")
        N = contact_rows(model, ref, q, contact_set)
        v0, v1 = N @ qd, N @ qd_plus
        T0, T1 = ref.energy(q, qd)[0], ref.energy(q, qd_plus)[0]
        assert F.min() >= 0.0
        assert v1.min() >= -1e-9 * np.abs(v0).max(), trial
        assert T1 <= T0 * (1 + 1e-10), trial
        if elastic:
            assert abs(T1 - T0) <= 1e-10 * T0, trial
        if v0.min() >= 0:
            assert np.array_equal(qd_plus, qd)          # nothing approaches: nothing happens


def test_one_round_is_eq47_when_every_approaching_contact_pushes(compiled):
    """Contacts that all approach and all push under Eq. 47: the law is Eq. 47 (the equality kernel)."""
    scene = chain(2, twists=True)
    model = compiled(scene)
    rng = np.random.default_rng(4)
    found = 0
    for trial in range(300):
        q, qd = reference.random_state(2, rng)
        contact_set = sorted(rng.choice(len(model.contacts), size=2, replace=False).tolist())
        if model.contacts[contact_set[0]][0] == model.contacts[contact_set[1]][0]:
            continue
        qd_eq, F_eq = model.impact(q, qd, contact_set)
        ref = reference_of(scene)
        v = contact_rows(model, ref, q, contact_set) @ qd
        if v.max() >= 0 or F_eq.min() <= 0:
            continue
        qd_plus, F = model.impact(q, qd, contact_set, mode="complementarity")
        assert np.allclose(qd_plus, qd_eq, rtol=1e-12, atol=1e-12 * np.abs(qd).max())
        assert np.allclose(F, F_eq, rtol=1e-10)
        found += 1
    assert found >= 5


def test_separating_contact_in_the_window_is_not_made_to_approach(compiled):
    """The class of a rod whose first end strikes its wall while the second, within contact_tol of the
    same wall, moves away: the second takes an impulse only if the first's impulse drives it into the wall,
    and it never leaves approaching (the printed Eq. 48 over both imposes v+ = -e v- on it: approach)."""
    scene = chain(1)
    model = compiled(scene)
    ref = reference_of(scene)
    wall = "x1_min"
    o1, o2 = (next(c for c, (pt, w) in enumerate(model.contacts) if pt == point and w.name == wall) for point in (1, 2))
    rng = np.random.default_rng(2)
    names = scene.parameter_names()
    p = scene.parameter_vector().copy()
    p[names.index(f"e_{wall}")] = 0.5
    hits = 0
    for trial in range(200):
        q, qd = reference.random_state(1, rng)
        N = contact_rows(model, ref, q, [o1, o2])
        v = N @ qd
        if not (v[0] < 0 < v[1]):
            continue
        qd_eq, _ = model.impact(q, qd, [o1, o2], p)
        qd_plus, F = model.impact(q, qd, [o1, o2], p, mode="complementarity")
        assert (N @ qd_plus).min() >= -1e-9 * np.abs(v).max()
        assert F.min() >= 0
        hits += (N @ qd_eq)[1] < 0                       # where Eq. 48 over both would make it approach
    assert hits >= 10


def test_mixed_restitutions_gain_energy_only_without_complementarity(compiled):
    """Walls with e = 0 and e = 1 struck together (2 to 4 contacts on random twisted 3-link chains): Eq. 48 as printed
    (every contact v+ = -e v-, impulses free to pull) gains kinetic energy on some states, while the law with
    complementarity never does: each round changes T by 1/2 sum (1 - e_a) F_a v-_a <= 0 (F_a > 0 only where
    v-_a <= 0), whatever the e's, so the frictionless law needs no common-e fallback (the frictional law's comes from
    its tangential part, (1 - e_a) Lambda_T . gamma_T-, of either sign).  The frictional entry point with law
    'frictionless' agrees, and never reports a common e."""
    scene = chain(3, twists=True)
    model = compiled(scene)
    rng = np.random.default_rng(47)
    names = scene.parameter_names()
    gains, worst = 0, 0.0
    for trial in range(300):
        p = random_parameters(scene, seed=4700 + trial)
        for i, name in enumerate(names):
            if name.startswith("e_"):
                p[i] = rng.choice([0.0, 1.0])
        q, qd = reference.random_state(3, rng)
        points = rng.choice(np.arange(1, 5), size=int(rng.integers(2, 5)), replace=False)
        contact_set = [int(rng.choice([c for c, (pt, w) in enumerate(model.contacts) if pt == point]))
                       for point in points]
        T0 = model.energy(q, qd, p)[0]
        qd_eq, _ = model.impact(q, qd, contact_set, p, mode="equality")
        gains += model.energy(q, qd_eq, p)[0] > T0 * (1 + 1e-6)
        qd_plus, _ = model.impact(q, qd, contact_set, p, mode="complementarity")
        worst = max(worst, (model.energy(q, qd_plus, p)[0] - T0) / T0)
        frictional = model.impact_friction(q, qd, contact_set, p, law="frictionless")
        assert frictional.law == "frictionless", trial
        assert model.energy(q, frictional.qd_plus, p)[0] <= T0 * (1 + 1e-10), trial
    assert gains >= 10                                  # the printed law's gain is common with mixed e
    assert worst <= 1e-12                               # the complementarity law's: round-off at most


def test_the_frictional_entry_on_a_model_without_friction_stays_in_its_work_array(compiled):
    """gac_impact_friction on a model with no rough wall: its work array is the smaller one (no room for the
    frictional law's W), so the law is the frictionless rounds whatever was asked; a sentinel past the array's end
    stays untouched (a frictional solve there wrote beyond it and corrupted the heap)."""
    scene = chain(3, twists=True)
    model = compiled(scene)
    rng = np.random.default_rng(5)
    size = model.size("IMPACT_NWORK")
    q, qd, p = rng.uniform(-1, 1, model.nq), rng.normal(size=model.nq) * 2, model.parameters()
    contact_set = np.ascontiguousarray([0, 3, 6][: min(3, model.nq)], dtype=np.int32)
    n = len(contact_set)
    for law in ("gdi", "newton-coulomb", "frictionless"):
        work = np.full(size + 4 * model.nq * model.nq, 12345.0)
        qd_plus, impulse, impulse_t = np.zeros(model.nq), np.zeros(n), np.zeros(2 * n)
        law_used, residual = model.ffi.new("int *"), model.ffi.new("double *")
        code = model.lib.gac_impact_friction(
            model.ffi.addressof(model.c.model), model._ptr(q), model._ptr(qd), model._ptr(p), n,
            model.ffi.cast("int *", model.ffi.from_buffer(contact_set)), model.impact_law_code(law),
            model._ptr(qd_plus), model._ptr(impulse), model._ptr(impulse_t), law_used, residual, model._ptr(work))
        assert code == model.lib.GAC_OK, law
        assert np.all(work[size:] == 12345.0), law                      # nothing written past the array
        assert model.impact_law_name(law_used[0]) == "frictionless" and np.all(impulse_t == 0.0)
        expected, _ = model.impact(q, qd, contact_set, p, mode="complementarity")
        assert np.allclose(qd_plus, expected, rtol=1e-9, atol=1e-12), law
