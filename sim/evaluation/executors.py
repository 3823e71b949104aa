"""Where an experiment's trials run: this process, worker processes of this machine, or Ray actors."""

from __future__ import annotations

import importlib.util
import json
import os
import signal
import socket
import sys
from collections import OrderedDict
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import urlsplit

from ..model.model import SimulationUnstable
from .experiment import Experiment, Trial, trial_spec
from .results_file import ResultsFile, trial_record, unplaceable_record


@dataclass(frozen=True)
class Watch:
    """Where a runner shows its trials (host/view.py): a live view's server, a recording file; either may be None."""

    live_url: str | None = None
    recording: Path | None = None


BRIDGES_KEPT = 3  # models a runner keeps loaded (a fidelity gate alternates two)


class TrialRunner:
    """Runs trials in this process: the firmware core in-process (no pty) and the MuJoCo model of the trial's rig.

    The runner keeps a bridge for each of the last BRIDGES_KEPT rigs it ran, each with a link of its own (the
    firmware runs on across trials, as a board does, and a bridge's firmware clock never goes back): the two
    controllers of one plant share one, and a fidelity gate's trials, which alternate two meshes, load each model
    once. With a watch, each trial is streamed to the view as a recording of its own, named by its cell and trial
    number.
    """

    def __init__(self, experiment: Experiment | None = None, watch: Watch | None = None) -> None:
        self.experiment, self.watch = experiment, watch
        self._bridges: OrderedDict[str, object] = OrderedDict()  # rig key -> its Bridge, the last used last
        self._rig_key: str | None = None
        self._unstable: tuple[str, SimulationUnstable] | None = None  # the last rig that would not load

    def _bridge(self, experiment: Experiment):
        from mantaray.host.link import Link
        from mantaray.host.transport import InProcessTransport

        from ..trial.bridge import Bridge

        key = json.dumps(
            [
                experiment.object_name,
                experiment.plant,
                experiment.plant_set,
                experiment.resolution,
                experiment.timestep_s,
            ]
        )
        if self._unstable is not None and self._unstable[0] == key:
            raise self._unstable[1]  # the same rig diverges the same way: do not load it again
        bridge = self._bridges.pop(key, None)
        if bridge is None:
            link = Link(InProcessTransport(simulated_clock=True))
            try:
                bridge = Bridge(link, experiment.rig(), experiment.plant_model().tracking())
            except SimulationUnstable as exc:
                self._unstable = (key, exc)
                raise
            while len(self._bridges) >= BRIDGES_KEPT:
                self._bridges.popitem(last=False)
        self._bridges[key] = bridge
        self._rig_key = key
        return bridge

    def result(self, trial: Trial, experiment: Experiment | None = None):
        """The bridge.TrialResult of one trial of the experiment (default: the runner's own)."""
        experiment = experiment or self.experiment
        bridge = self._bridge(experiment)
        view = self._show(bridge, experiment, trial) if self.watch is not None else None
        try:
            return bridge.run(trial_spec(experiment, trial))
        except SimulationUnstable as exc:  # this rig diverges: its other trials are refused without running
            self._unstable = (self._rig_key, exc)
            raise
        finally:
            if view is not None:
                bridge.view = None
                view.close()

    def _show(self, bridge, experiment: Experiment, trial: Trial):
        """The trial's view, attached to the bridge: a TrialView the caller closes."""
        from mantaray.host.view import REPORTED_ACTUATORS, RunView

        from ..trial.trial_view import TrialView

        assert self.watch is not None
        frame = bridge.rig.module
        view = RunView(
            "mantaray_sim_trials",
            self.watch.recording,
            self.watch.live_url,
            {
                **experiment.to_json(),
                "cell": trial.cell,
                "trial": trial.k,
                "start_m": trial.start_m,
                "seed": trial.seed,
            },
            REPORTED_ACTUATORS,
            (frame.size_x_m, frame.size_y_m),
            lambda text: print(f"mantaray sim: {text}", file=sys.stderr),
            world=True,
            name=f"cell{trial.cell}_trial{trial.k}",
        )
        bridge.view = TrialView(view, bridge.model, bridge.data, bridge.rig, bridge.link)
        return bridge.view

    def run(self, trial: Trial, experiment: Experiment | None = None) -> dict:
        """The record of one trial of the experiment (default: the runner's own)."""
        try:
            result = self.result(trial, experiment)
        except ValueError as exc:  # model.fabric_height: the start is not over the fabric
            if "not over the fabric" not in str(exc):
                raise
            return unplaceable_record(trial, str(exc))
        return trial_record(trial, result)

    def call(self, fn: Callable, arg):
        """fn(self, arg): a job that needs this process's runner (a Ray actor's, or a pool worker's)."""
        return fn(self, arg)


_worker: TrialRunner | None = None


def _init_worker(watch: Watch | None = None, claim=None) -> None:
    """A pool worker's runner; the first worker to take the claim (a shared flag) shows its trials in the watch."""
    global _worker
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle: no traceback per worker
    shows = False
    if claim is not None:
        with claim.get_lock():
            shows, claim.value = not claim.value, True
    _worker = TrialRunner(watch=watch if shows else None)


def _run_in_worker(job: tuple[object, dict, Trial]) -> tuple[object, dict]:
    """(tag, record) of one (tag, experiment, trial) job: the tag says where the record belongs."""
    tag, experiment_json, trial = job
    return tag, _worker.run(trial, Experiment.from_json(experiment_json))


def _call_in_worker(job: tuple[Callable, object]) -> object:
    fn, arg = job
    return _worker.call(fn, arg)


class LocalPool:
    """Worker processes of this machine that run (protocol, trial) jobs; `jobs` = 1 runs them in this process.
    With a watch, one worker (this process, when jobs = 1) shows the trial it is running."""

    def __init__(self, jobs: int, watch: Watch | None = None) -> None:
        self.jobs, self.watch = jobs, watch
        self._pool = None
        self._runner = TrialRunner(watch=watch) if jobs == 1 else None

    def __enter__(self) -> LocalPool:
        if self.jobs > 1:
            import multiprocessing

            context = multiprocessing.get_context("forkserver")
            claim = context.Value("b", False) if self.watch is not None else None
            self._pool = context.Pool(self.jobs, initializer=_init_worker, initargs=(self.watch, claim))
        return self

    def __exit__(self, *exc) -> None:
        if self._pool is not None:
            self._pool.terminate() if exc[0] is not None else self._pool.close()
            self._pool.join()

    def imap(self, jobs: list[tuple[Experiment, Trial]], ordered: bool = False) -> Iterator[dict]:
        """Records as the jobs finish (in any order), or in the jobs' order."""
        tagged = [(None, p, t) for p, t in jobs]
        if ordered and self._pool is not None:
            tagged_records = self._pool.imap(
                _run_in_worker, [(tag, p.to_json(), t) for tag, p, t in tagged], chunksize=1
            )
        else:
            tagged_records = self.imap_tagged(tagged)
        for _, record in tagged_records:
            yield record

    def imap_tagged(self, jobs: list[tuple[object, Experiment, Trial]]) -> Iterator[tuple[object, dict]]:
        """(tag, record) as the jobs finish, in any order: the tag (picklable) says where a record belongs when the
        jobs are of several protocols."""
        if self._pool is None:
            for tag, experiment, trial in jobs:
                yield tag, self._runner.run(trial, experiment)
            return
        yield from self._pool.imap_unordered(_run_in_worker, [(tag, p.to_json(), t) for tag, p, t in jobs], chunksize=1)

    def map(self, jobs: list[tuple[Experiment, Trial]]) -> list[dict]:
        """The jobs' records, in the jobs' order."""
        return list(self.imap(jobs, ordered=True))

    def map_calls(self, fn: Callable, args: list) -> list:
        """[fn(runner, a) for a in args] on the workers, each with its process's TrialRunner (fn a module-level
        function), in order."""
        if self._pool is None:
            return [self._runner.call(fn, a) for a in args]
        return self._pool.map(_call_in_worker, [(fn, a) for a in args], chunksize=1)


RAY_CONNECT_TIMEOUT_S = 10.0  # [s] how long a cluster's address may take to answer before a run gives up on it
RAY_DEFAULT_PORTS = {"": 6379, "ray": 10001}  # a head's GCS port, and its Ray Client server's (ray://), when unnamed


class RayUnavailable(Exception):
    """Ray cannot run the trials as asked (not installed, Ray Client missing, no cluster at the address); the message
    says so in one line, and what to do."""


def check_ray(address: str | None) -> None:
    """Before any work: Ray is installed; for a cluster's address (but "auto", Ray's own search of this machine), Ray
    Client is too where the address is a ray:// one, and the address accepts a connection within
    RAY_CONNECT_TIMEOUT_S (ray.init would retry an unreachable one for many minutes)."""
    if importlib.util.find_spec("ray") is None:
        raise RayUnavailable("--executor ray needs Ray: pip install 'mantaray[ray]'")
    if address in (None, "auto"):
        return
    scheme, _, where = address.rpartition("://")
    if scheme not in RAY_DEFAULT_PORTS:
        raise RayUnavailable(
            f"--ray-address is HOST:PORT (a cluster's head) or ray://HOST:PORT (its Ray Client server), got {address!r}"
        )
    if scheme == "ray" and importlib.util.find_spec("grpc") is None:
        raise RayUnavailable(
            f'--ray-address {address} goes through Ray Client, which is not installed: pip install "ray[client]"'
        )
    try:
        parts = urlsplit(f"//{where}")
        host, port = parts.hostname, parts.port or RAY_DEFAULT_PORTS[scheme]
    except ValueError:
        host = None
    if not host:
        raise RayUnavailable(f"--ray-address {address}: expected HOST:PORT after the scheme")
    try:
        socket.create_connection((host, port), timeout=RAY_CONNECT_TIMEOUT_S).close()
    except OSError as exc:
        raise RayUnavailable(
            f"--ray-address {address}: no connection to port {port} of {host} within "
            f"{RAY_CONNECT_TIMEOUT_S:g} s ({exc.strerror or exc}); is the cluster up, and its port "
            f"open to this machine?"
        ) from None


class RayPool:
    """Ray actors (a cluster at address, or a local Ray instance of this process's own) that run (protocol, trial)
    jobs. The local instance listens on this machine's loopback only, not on every interface: Ray's single-machine
    mode (its default on macOS and Windows), which the environment selects when ray is first imported in a process."""

    def __init__(self, jobs: int | None, address: str | None) -> None:
        if address is None:  # Ray's single-machine mode: its node address is 127.0.0.1
            os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
        elif "://" not in address:  # an address that answers, but not as a head: Ray would wait 20 tries of 30 s
            os.environ.setdefault("RAY_py_gcs_connect_timeout_s", f"{RAY_CONNECT_TIMEOUT_S:g}")
            os.environ.setdefault("RAY_gcs_server_port_wait_time_s", "1")
        import ray
        from ray.util import ActorPool

        self._started = not ray.is_initialized()  # a Ray of this process's own, which ends with the pool
        if self._started:
            try:
                ray.init(
                    address=address or "local", include_dashboard=False, logging_level="ERROR", log_to_driver=False
                )
            except ConnectionError as exc:  # it answered, but not as a Ray cluster does
                why = str(exc).splitlines()[0].rstrip(".")
                raise RayUnavailable(f"--ray-address {address}: {why}; is a Ray cluster's head there?") from None
        actors_n = jobs or max(1, int(ray.cluster_resources().get("CPU", 1)))
        actor = ray.remote(num_cpus=1)(TrialRunner)
        self._pool = ActorPool([actor.remote() for _ in range(actors_n)])

    def __enter__(self) -> RayPool:
        return self

    def __exit__(self, *exc) -> None:
        if self._started:  # its processes would otherwise outlive the work for the rest of this process
            import ray

            ray.shutdown()

    def imap(self, jobs: list[tuple[Experiment, Trial]], ordered: bool = False) -> Iterator[dict]:
        """Records as the jobs finish (in any order), or in the jobs' order."""
        mapper = self._pool.map if ordered else self._pool.map_unordered
        yield from mapper(lambda actor, job: actor.run.remote(job[1], job[0]), jobs)

    def map(self, jobs: list[tuple[Experiment, Trial]]) -> list[dict]:
        """The jobs' records, in the jobs' order."""
        return list(self.imap(jobs, ordered=True))

    def map_calls(self, fn: Callable, args: list) -> list:
        """[fn(runner, a) for a in args] on the actors (which hold every CPU they asked for), in order."""
        return list(self._pool.map(lambda actor, a: actor.call.remote(fn, a), args))


def run_local(experiment: Experiment, todo: list[Trial], jobs: int, watch: Watch | None = None) -> Iterator[dict]:
    """Records of the trials as they finish, on `jobs` processes of this machine (1: this process), one of them
    shown in the watch (if any)."""
    with LocalPool(jobs, watch) as pool:
        yield from pool.imap([(experiment, t) for t in todo])


def run_ray(experiment: Experiment, todo: list[Trial], jobs: int | None, address: str | None) -> Iterator[dict]:
    """Records of the trials as they finish, on Ray actors (a cluster at address, or a local Ray instance)."""
    with RayPool(jobs, address) as pool:
        yield from pool.imap([(experiment, t) for t in todo])


def run_into(
    files: list[ResultsFile],
    jobs: list[tuple[int, Trial]],
    workers: int,
    progress: Callable[[dict], None] | None = None,
) -> None:
    """Run jobs of several results files, (index into files, trial), on `workers` local processes in any order,
    appending each record to its own file as it finishes."""
    with LocalPool(workers) as pool:
        for i, record in pool.imap_tagged([(i, files[i].experiment, t) for i, t in jobs]):
            files[i].append(record)
            if progress is not None:
                progress(record)


def run(results: ResultsFile, records: Iterable[dict], progress: Callable[[dict], None] | None = None) -> None:
    """Append every record to the results file as it arrives (the file is the only state a resumption needs)."""
    for record in records:
        results.append(record)
        if progress is not None:
            progress(record)
