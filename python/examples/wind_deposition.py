#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""wind_deposition.py - sand blown over a wall settles in its lee, and
sandslide avalanches the drift: two models coupled through the BMI.

The wind model (a few lines of numpy, below) blows from the west over the
wall of cases/wind_wall.ini.  Sand in saltation that crosses the wall
falls out of the slowed air in its lee: the deposition rate decays with the
distance d downwind of the wall, r = r0 g(t) exp(-d / L), zero on the wall
and upwind of it.  The lee is sheltered only below the wall's crest, so
the rate falls to zero where the drift reaches the crest height H (over
the last 5 cm below it: a drift at the crest sticks out into the wind).  The wind gusts: g(t) varies over
a 12 s period (Bagnold's flux goes as the cube of the wind speed).  After
50 s the wind drops, and in 30 s of calm the drift settles.

Every coupling interval (the BMI's time step, the case's output_every) the
wind model reads the surface (get_value), sets the rate for the next
interval (set_value of land_surface__net_deposition_rate) and sandslide
advances (update_until), avalanching the drift to the repose angle.  At the
end the volume the wind delivered (its own ledger: sum of r dt dx dy over
the flow cells) must equal what sandslide holds minus the initial volume
plus what left through the open east end, and the library's inflow count.

    PYTHONPATH=python /usr/bin/python3 python/examples/wind_deposition.py [--png PATH]

(with SANDSLIDE_LIBRARY=build/libsandslide.so.0, or after `make install`.)
--png draws the drift and the rate along the strip (needs matplotlib).
"""
import argparse
import configparser
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))        # this checkout's python/
from sandslide.bmi import SandslideBmi             # noqa: E402

CASE = os.path.join(HERE, "..", "..", "cases", "wind_wall.ini")
ELEV, RATE = "land_surface__elevation", "land_surface__net_deposition_rate"

# the wind model's parameters
R0 = 3e-2          # m/s: deposition rate at the wall's lee face in a mean wind
LENGTH = 0.25      # m: e-folding distance of the deposition downwind
CREST = 0.4       # m: the wall's height; the lee is sheltered below it,
SHELTER_RAMP = 0.05  # m: less and less over this depth below the crest
GUST_PERIOD = 12.0  # s
WIND_END = 50.0    # s: the wind drops


def read_case(path):
    """The grid and the fence's x extent from the case file."""
    c = configparser.ConfigParser(inline_comment_prefixes=(";",))
    c.read(path)
    g = c["grid"]
    x0, y0 = map(float, g.get("origin", "0 0").split())
    fence = [float(v) for v in c["wall fence"]["rect"].split()]
    return int(g["nx"]), int(g["ny"]), float(g["dx"]), float(g.get("dy", g["dx"])), x0, fence


class Wind:
    """Deposition in the lee of a wall across the strip, the wind from the west."""

    def __init__(self, x, fence_x0, fence_x1):
        self.d = x - fence_x1                         # m downwind of the lee face
        self.lee = self.d > 0.0                       # not on the wall, not upwind
        self.wall = (x >= fence_x0) & (x <= fence_x1)

    def gust(self, t):
        """Sand flux relative to the mean wind's (the cube of the speed)."""
        if t >= WIND_END:
            return 0.0
        return (1.0 + 0.3 * math.sin(2.0 * math.pi * t / GUST_PERIOD)) ** 3

    def rate(self, t, h):
        """m/s of deposition for the heights h [y][x], over the next interval."""
        shelter = np.clip((CREST - h) / SHELTER_RAMP, 0.0, 1.0)
        r = R0 * self.gust(t) * np.exp(-np.where(self.lee, self.d, 0.0) / LENGTH) * shelter
        return np.where(self.lee, r, 0.0)


def simulate(case=CASE):
    """Run the coupled models; a dict of what the checks need."""
    nx, ny, dx, dy, x0, fence = read_case(case)
    x = x0 + (np.arange(nx) + 0.5) * dx                # cell centres, m
    wind = Wind(np.broadcast_to(x, (ny, nx)), fence[0], fence[2])
    flow = ~wind.wall                                   # the case's only walls
    scalar = np.empty(1)

    def value(m, name):
        return float(m.get_value(name, scalar)[0])

    with SandslideBmi() as m:
        m.initialize(case)
        shape = tuple(m.get_grid_shape(0, np.empty(2, dtype=int)))
        assert shape == (ny, nx), f"grid {shape}, the case says {(ny, nx)}"
        h = m.get_value(ELEV, np.empty(shape))
        h0, v0 = h.copy(), value(m, "sand__volume")
        delivered = 0.0
        t, end, step = m.get_current_time(), m.get_end_time(), m.get_time_step()
        while t < end:
            r = wind.rate(t, h)
            m.set_value(RATE, r)
            t_next = min(t + step, end)
            m.update_until(t_next)
            delivered += np.sum(r[flow]) * (t_next - t) * dx * dy
            t = m.get_current_time()
            m.get_value(ELEV, h)
        out = {name: value(m, name) for name in
               ("sand__volume", "sand__time_integral_of_source_volume_flux",
                "sand__time_integral_of_outflow_volume_flux",
                "sand__external_volume_change", "sand_surface__max_of_slope_angle")}
    out.update(h=h, h0=h0, x=x, v0=v0, delivered=delivered, fence=fence, dx=dx, dy=dy,
               wall=wind.wall, lee=wind.lee, rate_mean=wind.rate(0.0, h0 * 0), end=end)
    return out


def check(r):
    """The volume balance and the drift; AssertionError when off."""
    volume, outflow = r["sand__volume"], r["sand__time_integral_of_outflow_volume_flux"]
    held = volume - r["v0"] + outflow - r["sand__external_volume_change"]
    # Both sides are sums of roundings: the ledgers are compensated sums
    # (exact to an ulp or so), the volume a plain sum over the 480 cells;
    # doc/model.md#conservation asks 1e-12 of the poured volume of any run.
    tol = 1e-12 * r["delivered"]
    assert abs(held - r["delivered"]) <= tol, \
        f"the balance is off by {held - r['delivered']:.3g} m3 of {r['delivered']:.6g}"
    inflow = r["sand__time_integral_of_source_volume_flux"]
    assert abs(inflow - r["delivered"]) <= tol, \
        f"sandslide counted {inflow!r} m3 poured, the wind {r['delivered']!r}"
    rise = r["h"] - r["h0"]
    assert r["delivered"] > 0 and outflow >= 0
    assert np.all(rise[~r["lee"] & ~r["wall"]] == 0.0), "sand rose upwind of the wall"
    assert rise[r["lee"]].max() > 0.1, "no drift in the lee"
    return held


def draw(r, path):
    """The drift along the strip (its mean over y), the wall, a 35 deg line
    through the steepest point of the front, and the mean wind's rate."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    x, h = r["x"], r["h"].mean(axis=0)
    x0, _, x1, _ = r["fence"]
    fig, ax = plt.subplots(figsize=(6.4, 2.6), dpi=100)
    ax.fill_between([x0, x1], 0, CREST, color="0.35", label="wall")
    lee = r["lee"][0]
    xs, hs = np.r_[x1, x[lee]], np.r_[h[lee][0], h[lee]]     # from the lee face
    ax.fill_between(xs, 0, hs, color="#d9b36c", label=f"sand at {r['end']:g} s")
    k = np.nanargmax(-np.diff(np.where(lee, h, np.nan)))    # steepest mean slope
    xm, hm, t = 0.5 * (x[k] + x[k + 1]), 0.5 * (h[k] + h[k + 1]), math.tan(math.radians(35))
    ax.plot([xm - 0.15, xm + 0.15], [hm + 0.15 * t, hm - 0.15 * t], "k--", lw=1,
            label="35 deg")
    ax2 = ax.twinx()
    ax2.plot(x[lee], 1e3 * r["rate_mean"][0][lee], color="#3b6fb6", lw=1)
    ax2.set_ylabel("mean-wind rate, mm/s", color="#3b6fb6")
    ax2.set_ylim(0, 1e3 * R0 * 1.2)
    ax.set_xlabel("x, m (wind from the west)")
    ax.set_ylabel("height, m")
    ax.set_ylim(0, 0.6)
    ax.set_xlim(x[0] - r["dx"] / 2, x[-1] + r["dx"] / 2)
    ax.legend(loc="upper left", fontsize=8, frameon=False)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def main(argv=None):
    """The command line; the results of simulate, checked."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--case", default=CASE, help="the case file (default %(default)s)")
    p.add_argument("--png", help="draw the result into this PNG (needs matplotlib)")
    a = p.parse_args(argv)
    r = simulate(a.case)
    held = check(r)
    print(f"wind delivered     {r['delivered']:.15g} m3")
    print(f"sandslide holds    {r['sand__volume'] - r['v0']:.15g} m3 more than at t = 0")
    print(f"left by the open east end {r['sand__time_integral_of_outflow_volume_flux']:.15g} m3")
    print(f"balance: held + outflow - delivered = {held - r['delivered']:.3g} m3 "
          f"({abs(held - r['delivered']) / r['delivered']:.2g} relative)")
    # the wall's cells have no elevation: get_value gives NaN there
    print(f"drift: {np.nanmax(r['h']):.4f} m high, steepest sand face "
          f"{r['sand_surface__max_of_slope_angle']:.6f} deg")
    if a.png:
        draw(r, a.png)
        print(f"wrote {a.png}")
    return r


if __name__ == "__main__":
    main()
