"""The evaluation's charts (PNG): speed against accuracy, transition cost against valence, the
rigid blade's stiffness against the length of edge over bone, the force along strokes through
cut and uncut tissue."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hapticut_evaluation import methods


def speed_vs_error(accuracy_rows: list[dict], out: Path) -> None:
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (speed, memory) = plt.subplots(1, 2, figsize=(12, 5))
    styles = {methods.TET: "o-", methods.SHADED: "s-", methods.GOD: "^-", methods.VOXEL: "D--"}
    for family, style in styles.items():
        rows = [r for r in accuracy_rows if r["method"] == family and r["rate_Hz"] == 1000.0]
        if not rows:
            continue
        rows.sort(key=lambda r: (r["faces"], -r["voxel_mm"]))
        x = [r["ns_per_update"] for r in rows]
        y = [max(r["dir_err_mean_deg"], 1e-3) for r in rows]
        speed.plot(x, y, style, label=family)
        memory.plot([r["memory_bytes"] / 1024 for r in rows], y, style, label=family)
        for k, (r, xi, yi) in enumerate(zip(rows, x, y, strict=True)):
            tag = f"{r['voxel_mm']:g} mm" if family == methods.VOXEL else str(r["faces"])
            offset = (4, 3)
            if family == methods.VOXEL:
                # The voxel sizes sit close together: label the first and last only.
                if 0 < k < len(rows) - 1:
                    continue
                offset = (-14, -12) if k == 0 else (2, -12)
            speed.annotate(tag, (xi, yi), textcoords="offset points", xytext=offset, fontsize=7)
            memory.annotate(
                tag,
                (r["memory_bytes"] / 1024, yi),
                textcoords="offset points",
                xytext=(4, 3) if family != methods.VOXEL else (-8, -12),
                fontsize=7,
            )
    for ax in (speed, memory):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel("mean force-direction error (deg), 1 kHz")
        ax.grid(True, which="both", alpha=0.3)
    # Plain tick labels on the time axis (the log scale's minor labels overlap).
    ticks = [t for t in (10, 20, 50, 100, 200, 500, 1000, 2000, 5000)]
    speed.xaxis.set_major_locator(matplotlib.ticker.FixedLocator(ticks))
    speed.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
    speed.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    speed.axhline(0.3, color="grey", lw=0.8, ls=":")
    speed.annotate(
        "0.3 deg: the shading target",
        (speed.get_xlim()[0], 0.3),
        textcoords="offset points",
        xytext=(2, 3),
        fontsize=7,
        color="grey",
    )
    speed.set_xlabel("ns per point update (wall clock)")
    speed.set_title("Speed against accuracy, sphere r = 30 mm (labels: faces / voxel size)")
    memory.set_xlabel("memory of the method's model (KiB)")
    memory.set_title("Memory against accuracy")
    speed.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)


def valence(rows: list[dict], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    colours = {
        "widen": "tab:green",
        "scan": "tab:blue",
        "stay": "tab:blue",
        "face": "tab:orange",
        "edge": "tab:purple",
    }
    for element, marker in (("edge", "o"), ("vertex", "s")):
        for case, colour in colours.items():
            sel = sorted(
                (r for r in rows if r["element"] == element and r["case"] == case),
                key=lambda r: r["valence"],
            )
            if not sel:
                continue
            x = np.array([r["valence"] for r in sel], float)
            y = np.array([r["ns"] for r in sel], float)
            # Points only (the fans come from different mesh families), and the
            # least-squares line ns = fixed + per tet x valence through them.
            ax.plot(
                x,
                y,
                marker,
                color=colour,
                mfc=colour if element == "edge" else "none",
                label=f"{element} {case}",
            )
            if len(sel) >= 2:
                slope, fixed = np.polyfit(x, y, 1)
                span = np.linspace(x.min(), x.max(), 50)
                ax.plot(span, fixed + slope * span, "-", color=colour, lw=0.8, alpha=0.6)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("tets around the edge or vertex (valence)")
    ax.set_ylabel("ns per transition (median; widen: mean over targets)")
    ax.set_title("One EDGE / VERTEX transition against valence")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def rigid_stiffness(rows: list[dict], out: Path) -> None:
    """Stiffness felt against the points over bone: independent points grow with contact, the
    rigid blade renders every spring at every length."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    n = np.array([r["points_over_bone"] for r in rows], float)
    for key, label, style in (
        ("independent_points_N_per_mm", "independent points", "o-"),
        ("rigid_free_N_per_mm", "rigid, orientation free", "s-"),
        ("rigid_locked_N_per_mm", "rigid, orientation locked", "x--"),
    ):
        ax.plot(n, [r[key] for r in rows], style, label=label)
    ax.plot(n, [r["n_k_N_per_mm"] for r in rows], ":", color="grey", label="n k")
    ax.set_xscale("log")
    ax.set_xticks(n, [f"{int(v)}" for v in n])
    ax.set_xlabel("points of the 50-point blade over the bone")
    ax.set_ylabel("stiffness felt (N/mm)")
    ax.set_title("A bone under part of a blade")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def cut_memory(slits: list[dict], presses: list[dict], out: Path) -> None:
    """|force| along the three passes through the flesh (against x) and the three presses
    through the skin (against the device's height), with the materials' bounds."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from hapticut_evaluation import cut_memory as cm

    fig, (slit, skin) = plt.subplots(1, 2, figsize=(11, 4.4))
    styles = ("-", "--", ":")
    for p, style in zip(slits, styles, strict=True):
        slit.plot(p["x_mm"], p["force_N"], style, lw=1.6, label=p["pass"])
    for p, style in zip(presses, styles, strict=True):
        skin.plot(p["z_mm"], p["force_N"], style, lw=1.6, label=p["pass"])
    skin.invert_xaxis()  # Down, as the tool goes: before the bounds' labels, set at the left.
    bounds = (
        (slit, cm.K * cm.FLESH_DRAG_MM, "k D, uncut"),
        (slit, cm.K * cm.FLESH_CUT_DRAG_MM, "k D, cut"),
        (skin, cm.SKIN_BREAK_N, "break force"),
        (skin, cm.K * cm.UNDER_SKIN_DRAG_MM, "k D, flesh under it"),
    )
    for ax, level, label in bounds:
        ax.axhline(level, color="grey", lw=0.7, ls=":")
        ax.annotate(
            label,
            (ax.get_xlim()[0], level),
            textcoords="offset points",
            xytext=(2, 3),
            fontsize=7,
            color="grey",
        )
    slit.axvspan(*cm.INSIDE_X_MM, color="tab:blue", alpha=0.06, lw=0)
    slit.set_xlabel("tool position along the stroke, x (mm); the flesh: |x| < 10")
    slit.set_title(f"Flesh (drag {cm.FLESH_DRAG_MM:g} mm), cut to drag {cm.FLESH_CUT_DRAG_MM:g} mm")
    skin.axvspan(-cm.SKIN_MM, 0.0, color="tab:orange", alpha=0.08, lw=0)
    skin.set_xlabel("tool height z (mm), pressing down; the skin: shaded")
    skin.set_title(f"Skin (breaks at {cm.SKIN_BREAK_N:g} N), cut to air, over flesh")
    for ax in (slit, skin):
        ax.set_ylabel("|force| (N)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="center left")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
