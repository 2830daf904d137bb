"""``nnm-view FILE.h5``: explore the NNMs of a model in the browser.

Loads the model and every branch stored in FILE.h5 (a shipped example when FILE is the name of
one and no such file exists; the aircraft without FILE), serves a viser page (one independent
session per browser tab) at once while the solver's kernels are compiled in the background,
prints the URL and runs until Ctrl-C.
"""
from __future__ import annotations

import argparse
import contextlib
import errno
import io
import logging
import socket
import sys
import threading
import time

import nnm_solver

from .state import SharedState
from .warmup import SolverWarmUp, warm_for
from .worker import one_line

log = logging.getLogger("nnm_viewer")


class ViewerError(Exception):
    """A start-up problem reported as one line (bad file, busy port)."""


def find_file(name):
    """(path, shipped) of ``name``: an existing file, else the shipped example of that name (the
    aircraft when ``name`` is None); one-line ViewerError listing the shipped examples otherwise."""
    from .examples import MissingFile, resolve_file
    try:
        return resolve_file(name)
    except MissingFile as exc:
        raise ViewerError(str(exc)) from None


def load(path):
    """(model, branches) of an nnm file; one-line ViewerError on any problem."""
    try:
        model = nnm_solver.load_model(path)
    except nnm_solver.NNMInputError as exc:
        raise ViewerError(str(exc)) from None
    except (OSError, ValueError, KeyError) as exc:
        raise ViewerError(f"{path}: cannot read the model ({one_line(exc)})") from None
    loader = getattr(nnm_solver, "load_branches", None)
    branches = []
    if loader is not None:
        try:
            branches = list(loader(path))
        except nnm_solver.NNMInputError as exc:
            raise ViewerError(str(exc)) from None
        except (OSError, ValueError, KeyError) as exc:
            raise ViewerError(f"{path}: cannot read the branches ({one_line(exc)})") from None
    return model, branches


def load_measured_file(path, model, dof=None):
    """The measured backbone of ``--measured`` (None without it); one-line ViewerError on a bad file."""
    if path is None:
        if dof is not None:
            raise ViewerError("--measured-dof needs --measured FILE")
        return None
    from .measured import load_measured
    try:
        return load_measured(path, model, dof)
    except nnm_solver.NNMInputError as exc:
        raise ViewerError(str(exc)) from None


def check_port(host, port):
    """Raise ViewerError if ``port`` cannot be bound on ``host`` (viser would silently take another)."""
    if not 0 < port < 65536:
        raise ViewerError(f"port {port} is not a valid TCP port (1..65535)")
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as exc:
        raise ViewerError(f"cannot resolve host {host!r} ({exc.strerror})") from None
    family, _, _, _, addr = infos[0]
    with socket.socket(family, socket.SOCK_STREAM) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind(addr)
        except OSError as exc:
            if exc.errno == errno.EADDRINUSE:
                raise ViewerError(f"port {port} on {host} is already in use; pass another with --port") from None
            raise ViewerError(f"cannot listen on {host}:{port} ({exc.strerror})") from None


class ViewerApp:
    """The server: shared state plus one Session per connected tab."""

    def __init__(self, model, branches=(), path=None, host="127.0.0.1", port=8080, start_job=None,
                 verbose=False, warm=None, measured=None):
        import viser
        from . import scene as sc

        self.shared = SharedState(model, path=path, branches=branches, solver_ready=False, measured=measured)
        self.start_job = start_job
        with contextlib.redirect_stdout(io.StringIO()):   # viser's own banner: we print one line
            self.server = viser.ViserServer(host=host, port=port, label="nnm-view", verbose=verbose)
        if self.server.get_port() != port:
            self.server.stop()
            raise ViewerError(f"port {port} on {host} is already in use; pass another with --port")
        self.host, self.port = host, port
        self.sessions = {}
        self._lock = threading.Lock()
        mesh = model.mesh if model.mesh is not None else sc.fallback_mesh(model.n)
        geom = sc.view_geometry(mesh.vertices)
        self.server.scene.set_up_direction("+z")
        # no image-based lighting: the client's environment map is prefiltered (PMREM) on the first frame,
        # which stalls software WebGL (headless Chromium, no GPU) for 10-14 s before anything is drawn
        # (issue 32); a hemisphere light gives the PBR materials about the same look
        self.server.scene.configure_environment_map(hdri=None)
        self.server.scene.add_light_hemisphere("/lights/hemisphere", sky_color=(255, 255, 255),
                                               ground_color=(120, 120, 120), intensity=1.0)
        cam = self.server.initial_camera
        cam.position = tuple(geom.camera_position)
        cam.look_at = tuple(geom.camera_look_at)
        cam.fov = float(geom.fov_deg) * 3.141592653589793 / 180.0
        self.geometry = geom
        self.server.on_client_connect(self._connect)
        self.server.on_client_disconnect(self._disconnect)
        # the solver's kernels are compiled in the background (about 30 s on the first start after
        # installing): the pages are served and drawn meanwhile, and show "preparing the solver"
        self.warm_up = SolverWarmUp(on_done=lambda seconds, error: self.shared.set_solver_ready(),
                                    warm=warm or warm_for(model, branches, self.shared.set_orbits_ready)).start()

    @property
    def url(self):
        """The address to open: the one the server listens on (http://127.0.0.1:8080 by default; a server
        on every interface, 0.0.0.0 or ::, is reached there too).  Not 'localhost', which a browser may
        resolve to ::1 first, where a server on 127.0.0.1 does not listen."""
        host = {"0.0.0.0": "127.0.0.1", "::": "[::1]"}.get(self.host, self.host)
        if ":" in host and not host.startswith("["):
            host = f"[{host}]"
        return f"http://{host}:{self.port}"

    def _connect(self, client):
        from .controls import Session
        t0 = time.perf_counter()
        session = Session(client, self.shared, start_job=self.start_job)
        log.info("tab %d connected: session built in %.3f s", client.client_id, time.perf_counter() - t0)
        with self._lock:
            self.sessions[client.client_id] = session

    def _disconnect(self, client):
        with self._lock:
            session = self.sessions.pop(client.client_id, None)
        if session is not None:
            session.close()

    def stop(self):
        with self._lock:
            sessions = list(self.sessions.values())
            self.sessions.clear()
        for s in sessions:
            s.close()
        job = self.shared.job
        if job is not None:
            job.cancel()
        with contextlib.redirect_stdout(io.StringIO()):
            self.server.stop()


def parse_args(argv=None):
    p = argparse.ArgumentParser(prog="nnm-view", description="Explore the nonlinear normal modes of a model "
                                "in the browser (FEP picking, animated orbits, stiffness scaling).")
    p.add_argument("file", nargs="?", default=None,
                   help="nnm HDF5 file (model, mesh and branches), or the name of a shipped example "
                        "(paris.h5: the Paris-like aircraft, the default; two_dof.h5: the 2-DOF teaching model)")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    p.add_argument("--port", type=int, default=8080, help="TCP port (default 8080)")
    p.add_argument("--measured", metavar="BACKBONE", help="a measured backbone (.csv, .uff, .mat: peak amplitude "
                   "of one DOF against frequency) drawn on the FEP at the selected branch's energies (docs/testlab.md)")
    p.add_argument("--measured-dof", metavar="DOF", help="the model DOF of --measured (0-based index or DOF label; "
                   "default: the file's channel label)")
    p.add_argument("-v", "--verbose", action="store_true", help="log timings to stderr")
    return p.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    if args.verbose:
        logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s", stream=sys.stderr)
    try:
        path, shipped = find_file(args.file)
        model, branches = load(path)
        measured = load_measured_file(args.measured, model, args.measured_dof)
        check_port(args.host, args.port)
        app = ViewerApp(model, branches, path=path, host=args.host, port=args.port, measured=measured)
    except ViewerError as exc:
        print(f"nnm-view: error: {exc}", file=sys.stderr)
        return 2
    except nnm_solver.NNMInputError as exc:          # e.g. a model the solver cannot analyse
        print(f"nnm-view: error: {path}: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:                           # the web server could not start
        print(f"nnm-view: error: cannot serve on {args.host}:{args.port} ({one_line(exc)})", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    shown = f"{path.name} (shipped example)" if shipped and str(args.file or "") != str(path) else str(path)
    print(f"nnm-view: {shown}: {model.n} DOFs, {len(branches)} branch(es). Open {app.url} "
          f"in a browser (Ctrl-C to quit)", flush=True)
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        app.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
