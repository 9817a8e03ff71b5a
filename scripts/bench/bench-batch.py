"""Study throughput of glint against nilearn, in one run (scripts/bench/bench-batch runs it).

    python bench-batch.py MNI152.nii.gz GLINT_BIN READ_FLOOR_BIN OUT_DIR SUBJECTS SURFACE_SUBJECTS

Makes a BIDS study of SUBJECTS variants of the MNI152 template in OUT_DIR/study, then
times, on this machine's cores:
  - the read floor: READ_FLOOR_BIN (crates/io/examples/read_floor.rs) reads every
    input and inflates it with the inflater glint's readers use (flate2 on zlib-rs),
    parsing nothing; its CPU seconds per subject, before each round of `glint batch`,
    median of the rounds, are the least any reader of the study spends, and glint's
    CPU seconds per subject are printed as a multiple of them (issue 47: <= 2x);
  - `glint batch` (the command, --jobs = cores), median of GLINT_BENCH_ROUNDS rounds
    (default 3), every subject made (--force);
  - `glint.batch` on a Dask LocalCluster of one worker process per core (started and
    warmed before the clock; its start-up is printed apart), median of the rounds;
  - nilearn's plot_anat(display_mode="ortho") of every subject, one PNG each, on a pool
    of one spawned process per core (warmed: nilearn and matplotlib imported first);
  - nilearn's plot_img_on_surf (fsaverage5, both hemispheres, lateral and medial) of
    SURFACE_SUBJECTS subjects on the same pool.
Prints seconds and subjects per hour of each and the ratios; writes OUT_DIR/bench.json.
With GLINT_BENCH_GLINT_ONLY=1, times the read floor and `glint batch` only (no Dask,
no nilearn).

Each side's CPU seconds (user + system) are counted too: of the `glint batch` process,
of the Dask workers over a round, and of nilearn's figure calls in the pool processes.
On a machine other jobs share, wall seconds depend on how much of the cores each side
got while it ran; CPU seconds per subject do not, so the ratio of those is printed
beside the wall-clock one (on an idle machine the two agree when every side keeps
the cores busy).
"""

import json
import multiprocessing
import os
import resource
import statistics
import subprocess
import sys
import time

import nibabel as nib
import numpy as np

VIEWS = ["left", "anterior", "superior"]
SIZE = 256
PRESET = "mr-t2-brain"


def make_study(mni: str, root: str, n: int) -> list:
    """SUBJECTS variants of the template: a copy, mirrored left-right, intensities
    scaled by 0.8..1.2, Gaussian noise of 2% of the maximum, each with its origin moved
    by up to 5 mm; gzipped NIfTI in a BIDS layout. Returns the paths."""
    img = nib.load(mni)
    data = img.get_fdata(dtype=np.float32)
    rng = np.random.default_rng(32)
    os.makedirs(root, exist_ok=True)
    with open(os.path.join(root, "dataset_description.json"), "w") as f:
        json.dump({"Name": "glint bench-batch study", "BIDSVersion": "1.9.0"}, f)
    paths = []
    for s in range(1, n + 1):
        path = os.path.join(root, f"sub-{s:03d}", "anat", f"sub-{s:03d}_T1w.nii.gz")
        paths.append(path)
        if os.path.exists(path):
            continue
        kind = s % 4
        if kind == 1:
            vol = data[::-1].copy()
        elif kind == 2:
            vol = data * rng.uniform(0.8, 1.2)
        elif kind == 3:
            vol = data + rng.normal(0, 0.02 * float(data.max()), data.shape).astype(np.float32)
        else:
            vol = data
        affine = img.affine.copy()
        affine[:3, 3] += rng.uniform(-5, 5, 3)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        nib.save(nib.Nifti1Image(vol.astype(np.float32), affine), path)
    return paths


def warm():
    """Pool initialiser: the imports nilearn's figures need, before the clock."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot  # noqa: F401
    import nilearn.plotting  # noqa: F401


def cpu_seconds(who=resource.RUSAGE_SELF):
    """User plus system CPU seconds of this process (or its waited-for children)."""
    r = resource.getrusage(who)
    return r.ru_utime + r.ru_stime


def plot_anat(job):
    path, png = job
    import matplotlib.pyplot as plt
    from nilearn import plotting

    cpu = cpu_seconds()
    fig = plt.figure(figsize=(3 * SIZE / 100, SIZE / 100), dpi=100)
    display = plotting.plot_anat(path, display_mode="ortho", figure=fig)
    display.savefig(png, dpi=100)
    display.close()
    plt.close(fig)
    return cpu_seconds() - cpu


def plot_surf(job):
    path, png = job
    import matplotlib.pyplot as plt
    from nilearn import plotting

    cpu = cpu_seconds()
    plotting.plot_img_on_surf(path, surf_mesh="fsaverage5", hemispheres=["left", "right"],
                              views=["lateral", "medial"], colorbar=False, output_file=png)
    plt.close("all")
    return cpu_seconds() - cpu


def timed(f):
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


def main():
    mni, glint_bin, floor_bin, out, subjects, surface = sys.argv[1:7]
    subjects, surface = int(subjects), int(surface)
    rounds = int(os.environ.get("GLINT_BENCH_ROUNDS", "3"))
    glint_only = os.environ.get("GLINT_BENCH_GLINT_ONLY") == "1"
    cores = os.cpu_count() or 1
    study = os.path.join(out, "study")
    paths = make_study(mni, study, subjects)
    print(f"bench-batch: {subjects} subjects (MNI152 variants, {len(paths)} files), views "
          f"{','.join(VIEWS)} at {SIZE}x{SIZE}, {cores} cores, {rounds} rounds", file=sys.stderr)

    cpu = {"cli": [], "dask": [], "floor": []}

    def floor():
        before = cpu_seconds(resource.RUSAGE_CHILDREN)
        proc = subprocess.run([floor_bin, *paths], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
        cpu["floor"].append(cpu_seconds(resource.RUSAGE_CHILDREN) - before)

    def cli():
        before = cpu_seconds(resource.RUSAGE_CHILDREN)
        proc = subprocess.run([glint_bin, "batch", study, "-o", os.path.join(out, "cli"),
                               "--views", ",".join(VIEWS), "--size", f"{SIZE}x{SIZE}",
                               "--preset", PRESET, "--force", "-q"], capture_output=True, text=True)
        assert proc.returncode == 0, proc.stderr
        cpu["cli"].append(cpu_seconds(resource.RUSAGE_CHILDREN) - before)

    if glint_only:
        t_cli, t_floor = [], []
        for r in range(rounds):
            t_floor.append(timed(floor))
            t_cli.append(timed(cli))
            print(f"bench-batch: round {r + 1}/{rounds}: read floor {t_floor[-1]:.2f} s, "
                  f"glint batch {t_cli[-1]:.2f} s", file=sys.stderr)
        results = {"subjects": subjects, "cores": cores, "rounds": rounds, "views": VIEWS,
                   "size": SIZE, "glint_batch_s": statistics.median(t_cli),
                   "glint_batch_rounds_s": t_cli,
                   "glint_batch_cpu_s": statistics.median(cpu["cli"]),
                   "glint_batch_cpu_rounds_s": cpu["cli"]}
        print_floor(results, cpu["floor"], t_floor, subjects)
        with open(os.path.join(out, "bench.json"), "w") as f:
            json.dump(results, f, indent=1)
        return

    import glint
    from dask.distributed import Client, LocalCluster

    t = time.perf_counter()
    cluster = LocalCluster(n_workers=cores, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    client = Client(cluster)
    client.run(lambda: __import__("glint").Scene())
    startup = time.perf_counter() - t
    scene = glint.Scene(preset=PRESET, size=[SIZE, SIZE])

    def dask():
        before = sum(client.run(cpu_seconds).values())
        s = glint.batch.run(study, scene, VIEWS, os.path.join(out, "dask"), client=client,
                            force=True, progress=False)
        assert s["failed"] == 0, s
        cpu["dask"].append(sum(client.run(cpu_seconds).values()) - before)

    t_cli, t_dask, t_floor = [], [], []
    for r in range(rounds):
        t_floor.append(timed(floor))
        t_cli.append(timed(cli))
        t_dask.append(timed(dask))
        print(f"bench-batch: round {r + 1}/{rounds}: glint batch {t_cli[-1]:.2f} s, "
              f"glint.batch on Dask {t_dask[-1]:.2f} s", file=sys.stderr)
    client.close()
    cluster.close()

    os.makedirs(os.path.join(out, "nilearn"), exist_ok=True)
    anat_jobs = [(p, os.path.join(out, "nilearn", f"{i:03d}-anat.png")) for i, p in enumerate(paths)]
    surf_jobs = [(p, os.path.join(out, "nilearn", f"{i:03d}-surf.png"))
                 for i, p in enumerate(paths[:surface])]
    spawn = multiprocessing.get_context("spawn")
    with spawn.Pool(cores, initializer=warm) as pool:
        pool.map(warm_one, range(cores), chunksize=1)
        t = time.perf_counter()
        cpu_anat = sum(pool.map(plot_anat, anat_jobs, chunksize=1))
        t_anat = time.perf_counter() - t
        print(f"bench-batch: nilearn plot_anat {t_anat:.2f} s", file=sys.stderr)
        t = time.perf_counter()
        cpu_surf = sum(pool.map(plot_surf, surf_jobs, chunksize=1)) if surface else float("nan")
        t_surf = time.perf_counter() - t if surface else float("nan")
        print(f"bench-batch: nilearn plot_img_on_surf {t_surf:.2f} s ({surface} subjects)", file=sys.stderr)

    per_hour = lambda seconds, n: 3600.0 * n / seconds  # noqa: E731
    results = {
        "subjects": subjects, "surface_subjects": surface, "cores": cores, "rounds": rounds,
        "views": VIEWS, "size": SIZE,
        "glint_batch_s": statistics.median(t_cli), "glint_batch_rounds_s": t_cli,
        "dask_s": statistics.median(t_dask), "dask_rounds_s": t_dask, "dask_startup_s": startup,
        "nilearn_plot_anat_s": t_anat, "nilearn_plot_img_on_surf_s": t_surf,
        "glint_batch_cpu_s": statistics.median(cpu["cli"]), "glint_batch_cpu_rounds_s": cpu["cli"],
        "dask_cpu_s": statistics.median(cpu["dask"]), "dask_cpu_rounds_s": cpu["dask"],
        "nilearn_plot_anat_cpu_s": cpu_anat, "nilearn_plot_img_on_surf_cpu_s": cpu_surf,
        "load_average": os.getloadavg(),
    }
    rows = [
        ("glint batch (the command)", results["glint_batch_s"], results["glint_batch_cpu_s"], subjects),
        (f"glint.batch, Dask LocalCluster of {cores}", results["dask_s"], results["dask_cpu_s"], subjects),
        ("nilearn plot_anat, 3 cuts", t_anat, cpu_anat, subjects),
        ("nilearn plot_img_on_surf, 4 views", t_surf, cpu_surf, surface),
    ]
    print(f"{'':42} {'seconds':>9} {'per subject':>12} {'subjects/h':>11} {'CPU s/subject':>14}")
    for name, s, c, n in rows:
        print(f"{name:42} {s:9.2f} {s / n:12.3f} {per_hour(s, n):11.0f} {c / n:14.3f}")
    anat_each, anat_cpu = t_anat / subjects, cpu_anat / subjects
    for name, s, c, n in rows[:2]:
        ratio = anat_each / (s / n)
        cpu_ratio = anat_cpu / (c / n)
        surf = (t_surf / surface) / (s / n) if surface else float("nan")
        print(f"{name}: {ratio:.1f}x nilearn plot_anat's subjects/h ({cpu_ratio:.1f}x per CPU "
              f"second), {surf:.1f}x plot_img_on_surf's")
        key = "cli" if name.startswith("glint batch") else "dask"
        results[f"ratio_{key}_vs_plot_anat"] = ratio
        results[f"cpu_ratio_{key}_vs_plot_anat"] = cpu_ratio
    print_floor(results, cpu["floor"], t_floor, subjects)
    print(f"bench-batch: load average at the end {os.getloadavg()}", file=sys.stderr)
    with open(os.path.join(out, "bench.json"), "w") as f:
        json.dump(results, f, indent=1)


def print_floor(results, floor_cpu, floor_s, subjects):
    """The read floor's CPU seconds per subject beside `glint batch`'s, and their
    ratio (issue 47's target: at most 2), into `results` and on stdout."""
    floor = statistics.median(floor_cpu) / subjects
    glint_cpu = results["glint_batch_cpu_s"] / subjects
    results.update({"read_floor_cpu_s": statistics.median(floor_cpu),
                    "read_floor_cpu_rounds_s": floor_cpu, "read_floor_rounds_s": floor_s,
                    "glint_batch_cpu_vs_read_floor": glint_cpu / floor})
    print(f"read floor (read + inflate, zlib-rs): {floor:.3f} CPU s/subject; glint batch "
          f"{glint_cpu:.3f} CPU s/subject = {glint_cpu / floor:.2f}x the read floor "
          f"(wall {results['glint_batch_s']:.2f} s for {subjects} subjects, "
          f"{results['glint_batch_s'] / subjects:.3f} s each)")


def warm_one(_):
    """One task per pool process before the clock: each holds its process half a
    second, so every process has run its initialiser (the imports) and taken one."""
    time.sleep(0.5)
    return os.getpid()


if __name__ == "__main__":
    main()
