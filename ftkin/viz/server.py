"""Starting, attaching to and stopping a meshcat server (meshcat imported lazily).

``meshcat.Visualizer()`` starts ``meshcat.servers.zmqserver`` as a
subprocess. Its ``close()`` is broken in meshcat 0.3.2, so ftkin stops the
server process itself: kill, then wait (no zombie), and closes its ZMQ socket.
"""

import contextlib
import io
import logging

from ..exceptions import FtkinError, MissingDependency

logger = logging.getLogger(__name__)


def import_meshcat():
    """The ``meshcat`` module, or :class:`MissingDependency` naming the ``viz`` extra."""
    try:
        import meshcat
        import meshcat.animation  # noqa: F401
        import meshcat.geometry  # noqa: F401
    except ImportError:
        raise MissingDependency("meshcat", "viz", "the 3D view (ftkin.viz, ftkin view)") from None
    return meshcat


def load_arm(arm, visualizer):
    """Pinocchio's ``MeshcatVisualizer`` of ``arm`` (an :class:`~ftkin.kinematics.arm.Arm`) loaded
    into ``visualizer`` as the scene node ``pinocchio``: visual geometry, collision geometry hidden.
    """
    import_meshcat()
    try:
        from pinocchio.visualize import MeshcatVisualizer
    except ImportError:
        raise MissingDependency(
            "meshcat", "viz", "drawing the arm (pinocchio.visualize.MeshcatVisualizer)"
        ) from None
    robot = MeshcatVisualizer(arm.model, arm.geometry("collision"), arm.geometry("visual"))
    robot.initViewer(viewer=visualizer)
    robot.loadViewerModel(rootNodeName="pinocchio")
    return robot


def start_visualizer(zmq_url: str | None = None):
    """A ``meshcat.Visualizer``: a new server (``zmq_url=None``) or attached to a running one.

    meshcat prints the URL on stdout; that text is captured and logged instead.

    Raises:
        FtkinError: the server cannot be started or reached.
    """
    meshcat = import_meshcat()
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            visualizer = meshcat.Visualizer(zmq_url=zmq_url)
    except Exception as error:  # meshcat raises RuntimeError / zmq errors
        where = f"at {zmq_url}" if zmq_url else "as a subprocess"
        raise FtkinError(f"cannot start or reach the meshcat server {where}: {error}") from None
    logger.info("meshcat viewer at %s", visualizer.url())
    return visualizer


def stop_server(visualizer, timeout: float = 5.0) -> None:
    """Close the client socket and, when this process started the server, stop it.

    Safe to call twice. The server subprocess is killed and reaped (waited for).
    """
    window = visualizer.window
    socket = getattr(window, "zmq_socket", None)
    if socket is not None:
        socket.close(linger=0)  # a no-op on a closed socket
    process = getattr(window, "server_proc", None)
    if process is not None:
        if process.poll() is None:
            process.kill()
            process.wait(timeout=timeout)
        for stream in filter(None, (process.stdout, process.stderr)):
            stream.close()  # a no-op on a closed stream
