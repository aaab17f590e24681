"""Numba kernels of the neuron simulations (fast path).

Each kernel runs ``n_neurons`` independent neurons over ``n_steps`` fixed steps; step ``k``
starts at ``k * dt`` and uses the input sample ``sample_of_step[k]`` (zero-order hold). The
plain references are :func:`sim_tactile.encoders.izhikevich.simulate_reference` and
:func:`sim_tactile.encoders.lif.simulate_reference`; the tests demand equal spike times.

Outputs: ``times`` (all spike times in the kernel's time unit, grouped by neuron, each
neuron's in time order), ``counts`` (each neuron's spikes), and per-neuron diagnostics ``multi`` (steps in which the neuron fired
more than once, or, for the one-spike-per-step schemes, fired again on the very next step),
``capped`` (steps where more than ``max_per_step`` spikes would have been needed) and
``nonfinite`` (1 if the state overflowed; the simulation of that neuron stopped).
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit

RK4, EULER, IZH2003 = 0, 1, 2


@njit(inline="always")
def _rhs(v, u, cur, a, b):
    return (0.04 * v + 5.0) * v + 140.0 - u + cur, a * (b * v - u)


@njit(inline="always")
def _rk4(v, u, cur, a, b, h):
    k1v, k1u = _rhs(v, u, cur, a, b)
    k2v, k2u = _rhs(v + 0.5 * h * k1v, u + 0.5 * h * k1u, cur, a, b)
    k3v, k3u = _rhs(v + 0.5 * h * k2v, u + 0.5 * h * k2u, cur, a, b)
    k4v, k4u = _rhs(v + h * k3v, u + h * k3u, cur, a, b)
    return (
        v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
        u + h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u),
    )


@njit
def _rk4_all(v, u, vn, un, row, a, b, h):
    # the same arithmetic as _rk4, written out so that LLVM vectorises it across neurons
    for i in range(v.size):
        vi = v[i]
        ui = u[i]
        ci = row[i]
        ai = a[i]
        bi = b[i]
        k1v = (0.04 * vi + 5.0) * vi + 140.0 - ui + ci
        k1u = ai * (bi * vi - ui)
        x = vi + 0.5 * h * k1v
        y = ui + 0.5 * h * k1u
        k2v = (0.04 * x + 5.0) * x + 140.0 - y + ci
        k2u = ai * (bi * x - y)
        x = vi + 0.5 * h * k2v
        y = ui + 0.5 * h * k2u
        k3v = (0.04 * x + 5.0) * x + 140.0 - y + ci
        k3u = ai * (bi * x - y)
        x = vi + h * k3v
        y = ui + h * k3u
        k4v = (0.04 * x + 5.0) * x + 140.0 - y + ci
        k4u = ai * (bi * x - y)
        vn[i] = vi + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
        un[i] = ui + h / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u)


@njit
def _euler_all(v, u, vn, un, row, a, b, h):
    for i in range(v.size):
        vi = v[i]
        ui = u[i]
        vn[i] = vi + h * ((0.04 * vi + 5.0) * vi + 140.0 - ui + row[i])
        un[i] = ui + h * (a[i] * (b[i] * vi - ui))


@njit
def _izh2003_all(v, u, vn, un, row, a, b, h):
    for i in range(v.size):
        vi = v[i]
        ui = u[i]
        vi = vi + 0.5 * h * ((0.04 * vi + 5.0) * vi + 140.0 - ui + row[i])
        vi = vi + 0.5 * h * ((0.04 * vi + 5.0) * vi + 140.0 - ui + row[i])
        vn[i] = vi
        un[i] = ui + h * a[i] * (b[i] * vi - ui)


@njit
def _record(times, who, n_total, t, n):
    if n_total == times.size:
        t2 = np.empty(2 * times.size)
        w2 = np.empty(2 * times.size, dtype=np.int64)
        t2[:n_total] = times
        w2[:n_total] = who
        times, who = t2, w2
    times[n_total] = t
    who[n_total] = n
    return times, who, n_total + 1


@njit
def _rk4_spiking_step(v, u, cur, a, b, c, d, v_peak, t, dt, tol, max_per_step, times, who, nt, n):
    """The rare path: a rk4 step that reaches v_peak. Bisect the Runge-Kutta map to the
    crossing, reset, integrate the rest of the step; repeat while it keeps crossing."""
    rem = dt
    fired = 0
    capped = 0
    while rem > 0.0:
        vn, un = _rk4(v, u, cur, a, b, rem)
        if vn < v_peak:
            v = vn
            u = un
            break
        if fired == max_per_step:
            capped = 1
            break
        lo = 0.0
        hi = rem
        while hi - lo > tol * dt:
            mid = 0.5 * (lo + hi)
            vm, um = _rk4(v, u, cur, a, b, mid)
            if vm < v_peak:
                lo = mid
            else:
                hi = mid
        vm, um = _rk4(v, u, cur, a, b, hi)
        t += hi
        rem -= hi
        times, who, nt = _record(times, who, nt, t, n)
        fired += 1
        v = c
        u = um + d
    return v, u, fired, capped, times, who, nt


@njit
def izhikevich_run(
    current_t, sample_of_step, a, b, c, d, v_peak, v_init, dt, scheme, tol, max_per_step
):
    """Izhikevich neurons; time unit ms. ``current_t``: (n_samples, n_neurons), i.e. the input
    transposed so that the inner loop over neurons reads contiguous memory.

    Returns ``(times, counts, multi, capped, nonfinite)``: every spike time grouped by neuron
    (neuron 0's spikes in time order, then neuron 1's, ...), the spikes of each neuron, and
    the per-neuron diagnostics.
    """
    n_neurons = current_t.shape[1]
    v = np.full(n_neurons, v_init)
    u = b * v_init
    multi = np.zeros(n_neurons, dtype=np.int64)
    capped = np.zeros(n_neurons, dtype=np.int64)
    nonfinite = np.zeros(n_neurons, dtype=np.int64)
    if scheme == RK4:
        times, who, nt = _rk4_steps(
            current_t,
            sample_of_step,
            a,
            b,
            c,
            d,
            v_peak,
            v,
            u,
            dt,
            tol,
            max_per_step,
            multi,
            capped,
            nonfinite,
        )
    else:
        times, who, nt = _one_spike_steps(
            current_t, sample_of_step, a, b, c, d, v_peak, v, u, dt, scheme, multi, nonfinite
        )
    grouped, counts = group_by_neuron(times, who, nt, n_neurons)
    return grouped, counts, multi, capped, nonfinite


@njit
def group_by_neuron(times, who, nt, n_neurons):
    """The first ``nt`` spikes, recorded in time order, regrouped by neuron (a counting sort:
    stable, so each neuron's spikes stay in time order); and each neuron's count."""
    counts = np.zeros(n_neurons, dtype=np.int64)
    for j in range(nt):
        counts[who[j]] += 1
    start = np.empty(n_neurons, dtype=np.int64)
    acc = 0
    for n in range(n_neurons):
        start[n] = acc
        acc += counts[n]
    out = np.empty(nt)
    for j in range(nt):
        n = who[j]
        out[start[n]] = times[j]
        start[n] += 1
    return out, counts


@njit
def _rk4_steps(
    current_t,
    sample_of_step,
    a,
    b,
    c,
    d,
    v_peak,
    v,
    u,
    dt,
    tol,
    max_per_step,
    multi,
    capped,
    nonfinite,
):
    """The rk4 scheme: each step for every neuron branch-free (LLVM vectorises it across
    neurons), then the rare spiking path per neuron (:func:`_rk4_spiking_step`)."""
    n_neurons = v.size
    times = np.empty(1024)
    who = np.empty(1024, dtype=np.int64)
    nt = 0
    vn = np.empty(n_neurons)
    un = np.empty(n_neurons)
    for k in range(sample_of_step.size):
        row = current_t[sample_of_step[k]]
        _rk4_all(v, u, vn, un, row, a, b, dt)
        # the new state becomes current (swap, no copy); the spiking path (NaN also lands
        # here) restarts from the old state kept in vn, un
        v, vn = vn, v
        u, un = un, u
        for n in range(n_neurons):
            if v[n] < v_peak or nonfinite[n]:
                continue
            vr, ur, fired, cap, times, who, nt = _rk4_spiking_step(
                vn[n],
                un[n],
                row[n],
                a[n],
                b[n],
                c[n],
                d[n],
                v_peak,
                k * dt,
                dt,
                tol,
                max_per_step,
                times,
                who,
                nt,
                n,
            )
            v[n] = vr
            u[n] = ur
            if fired > 1:
                multi[n] += 1
            capped[n] += cap
            if not (math.isfinite(v[n]) and math.isfinite(u[n])):
                nonfinite[n] = 1
                v[n] = math.nan
    return times, who, nt


@njit
def _one_spike_steps(
    current_t, sample_of_step, a, b, c, d, v_peak, v, u, dt, scheme, multi, nonfinite
):
    """The papers' schemes (Euler, or the 2003 code's two half steps of ``v``): at most one
    spike per step, at the step's end. Each step for every neuron branch-free (vectorised),
    then the neurons that reached the peak (a fused loop measured slower:
    ``docs/spikes.md``)."""
    n_neurons = v.size
    times = np.empty(max(1024, 4 * n_neurons))
    who = np.empty(times.size, dtype=np.int64)
    nt = 0
    last = np.full(n_neurons, -2, dtype=np.int64)
    vn = np.empty(n_neurons)
    un = np.empty(n_neurons)
    for k in range(sample_of_step.size):
        row = current_t[sample_of_step[k]]
        t_end = (k + 1) * dt
        if scheme == EULER:
            _euler_all(v, u, vn, un, row, a, b, dt)
        else:
            _izh2003_all(v, u, vn, un, row, a, b, dt)
        v, vn = vn, v
        u, un = un, u
        for n in range(n_neurons):
            if v[n] < v_peak or nonfinite[n]:
                continue
            if nt == times.size:
                times, who, nt = _record(times, who, nt, t_end, n)
            else:
                times[nt] = t_end
                who[nt] = n
                nt += 1
            if last[n] == k - 1:
                multi[n] += 1
            last[n] = k
            v[n] = c[n]
            u[n] = u[n] + d[n]
            if not (math.isfinite(v[n]) and math.isfinite(u[n])):
                nonfinite[n] = 1
                v[n] = math.nan
    return times, who, nt


@njit(inline="always")
def _lif_free(v, adapt, cur, v_rest, tau_m, tau_a, t):
    v_inf = v_rest + cur
    return v_inf + (v - v_inf) * math.exp(-t / tau_m), adapt * math.exp(-t / tau_a)


@njit
def lif_run(
    current,
    sample_of_step,
    tau_m,
    v_rest,
    v_reset,
    v_th,
    refractory,
    tau_a,
    beta,
    dt,
    tol,
    max_per_step,
):
    """(Adaptive) LIF neurons, exact between events; time unit s. Parameters per neuron."""
    n_neurons = current.shape[0]
    n_steps = sample_of_step.size
    times = np.empty(1024)
    who = np.empty(1024, dtype=np.int64)
    n_total = 0
    multi = np.zeros(n_neurons, dtype=np.int64)
    capped = np.zeros(n_neurons, dtype=np.int64)
    nonfinite = np.zeros(n_neurons, dtype=np.int64)
    for n in range(n_neurons):
        v = v_rest[n]
        adapt = 0.0
        ref_left = 0.0
        for k in range(n_steps):
            cur = current[n, sample_of_step[k]]
            t = k * dt
            rem = dt
            fired = 0
            while rem > 0.0:
                if ref_left > 0.0:
                    adv = min(ref_left, rem)
                    adapt = adapt * math.exp(-adv / tau_a[n])
                    ref_left -= adv
                    t += adv
                    rem -= adv
                    continue
                ve, ae = _lif_free(v, adapt, cur, v_rest[n], tau_m[n], tau_a[n], rem)
                if ve < v_th[n] + ae:
                    v = ve
                    adapt = ae
                    break
                if fired == max_per_step:
                    capped[n] += 1
                    break
                lo = 0.0
                hi = rem
                while hi - lo > tol * dt:
                    mid = 0.5 * (lo + hi)
                    vm, am = _lif_free(v, adapt, cur, v_rest[n], tau_m[n], tau_a[n], mid)
                    if vm < v_th[n] + am:
                        lo = mid
                    else:
                        hi = mid
                vm, am = _lif_free(v, adapt, cur, v_rest[n], tau_m[n], tau_a[n], hi)
                t += hi
                rem -= hi
                times, who, n_total = _record(times, who, n_total, t, n)
                fired += 1
                v = v_reset[n]
                adapt = am + beta[n]
                ref_left = refractory[n]
            if fired > 1:
                multi[n] += 1
            if not (math.isfinite(v) and math.isfinite(adapt)):
                nonfinite[n] = 1
                break
    return times[:n_total].copy(), who[:n_total].copy(), multi, capped, nonfinite
