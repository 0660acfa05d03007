"""Start an rcssserver on loopback only, or reach a running one; UDP endpoints whose every receive has a timeout.

rcssserver binds its UDP sockets to every address and has no option to bind to one. :class:`ServerProcess` therefore
starts it inside a private network namespace that holds only ``lo`` (Linux ``unshare(CLONE_NEWUSER |
CLONE_NEWNET)``; as root ``CLONE_NEWNET`` alone when user namespaces are off), or refuses to start. The forked child
makes the namespace, brings ``lo`` up, chooses free ports there (bound with port 0, then released), opens the
client's two UDP sockets in it and hands them to this process over a socket pair before it executes the server, so
the client reaches the server through the namespace's loopback while the server is reachable from nowhere else.
The server runs in its own process group in a temporary folder that also holds its ``$HOME`` (rcssserver writes
``~/.rcssserver/*.conf``) and every log path, and it is stopped on leaving the ``with`` block (also on Ctrl-C or an
exception; the kernel kills it too should this process die first: ``PR_SET_PDEATHSIG``).
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import fcntl
import json
import os
import signal
import socket
import struct
import tempfile
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType

DEFAULT_TIMEOUT = 10.0
"""Seconds a receive waits for the server before it is an error."""
MAX_TIMEOUT = 3600.0
"""The longest wait allowed: a server silent for an hour is gone (and far longer waits overflow the socket's timer)."""
STOP_GRACE = 2.0
"""Seconds a stopped server has to exit after SIGTERM before it is killed."""
MAX_MESSAGE = 65536

Log = Callable[[str, str, str], None]
"""A transcript: called with ``(client, direction, text)`` for every message."""

_CLONE_NEWUSER, _CLONE_NEWNET = 0x10000000, 0x40000000
_PR_SET_PDEATHSIG = 1
_SIOCGIFFLAGS, _SIOCSIFFLAGS, _IFF_UP = 0x8913, 0x8914, 0x1


def checked_timeout(timeout: object) -> float:
    """``timeout`` as seconds.

    :raises ValueError: unless it is a number in ``(0, MAX_TIMEOUT]``
    """
    if isinstance(timeout, bool) or not isinstance(timeout, (int, float)) or not 0 < timeout <= MAX_TIMEOUT:
        raise ValueError(f"timeout must be a number of seconds in (0, {MAX_TIMEOUT:g}], got {timeout!r}")
    return float(timeout)


def checked_port(name: str, port: object) -> int:
    """``port`` as a UDP port number.

    :raises ValueError: unless it is a whole number in 1 .. 65535
    """
    if isinstance(port, bool) or not isinstance(port, int) or not 1 <= port <= 65535:
        raise ValueError(f"{name} must be a port number in 1 .. 65535, got {port!r}")
    return port


class ServerError(RuntimeError):
    """The server could not be started, died, never answered, or answered something other than the protocol."""


@dataclass(frozen=True)
class ServerPorts:
    """The UDP ports of one server: players, trainer (``server::coach_port``) and online coach."""

    player: int
    trainer: int
    online_coach: int


class Endpoint:
    """One client's UDP socket to the server: sends text messages and receives them with a timeout.

    The server answers a client's first message from a port of its own for that client; :meth:`receive` adopts the
    address of the first answer, as rcssserver clients do.

    :param sock: a UDP socket (closed by :meth:`close`).
    :param address: ``(host, port)`` the first message goes to.
    :param timeout: seconds a :meth:`receive` waits.
    :param alive: called when a receive times out; raises :class:`ServerError` if the server is known to be gone.
    :param name: the client's name in the transcript (``"player"``, ``"trainer"``).
    :param log: called with ``(name, direction, text)`` for every message (direction ``"sent"`` or ``"received"``).
    """

    def __init__(
        self,
        name: str,
        sock: socket.socket,
        address: tuple[str, int],
        timeout: float = DEFAULT_TIMEOUT,
        alive: Callable[[], None] | None = None,
        log: Log | None = None,
    ) -> None:
        self.name, self.sock, self.address, self.timeout = name, sock, address, checked_timeout(timeout)
        self._answered = False
        self._alive = alive
        self._log = log
        sock.settimeout(self.timeout)

    def send(self, text: str) -> None:
        if self._log is not None:
            self._log(self.name, "sent", text)
        try:
            self.sock.sendto(text.encode("ascii") + b"\0", self.address)
        except OSError as error:
            self._check_alive()
            raise ServerError(f"cannot send to the server at {self.address[0]}:{self.address[1]}: {error}") from None

    def receive(self) -> str:
        """The next message (without its terminating NUL).

        :raises ServerError: if none comes within the timeout, or the server is gone.
        """
        try:
            data, sender = self.sock.recvfrom(MAX_MESSAGE)
        except (TimeoutError, ConnectionRefusedError) as error:
            self._check_alive()
            what = "no answer" if isinstance(error, TimeoutError) else "connection refused"
            raise ServerError(
                f"{what} from the server at {self.address[0]}:{self.address[1]} within {self.timeout:g} s"
            ) from None
        if not self._answered:
            self.address, self._answered = sender, True
        text = data.rstrip(b"\0").decode("ascii", errors="replace")
        if self._log is not None:
            self._log(self.name, "received", text)
        return text

    def close(self) -> None:
        self.sock.close()

    def _check_alive(self) -> None:
        if self._alive is not None:
            self._alive()


def connect(
    host: str, ports: ServerPorts, timeout: float = DEFAULT_TIMEOUT, log: Log | None = None
) -> tuple[Endpoint, Endpoint]:
    """UDP endpoints ``(player, trainer)`` to a server that is already running at ``host`` (the caller keeps it on
    loopback, or where it likes).

    :raises ValueError: for a port outside 1 .. 65535 or a timeout outside ``(0, MAX_TIMEOUT]``
    """
    checked_port("ports.player", ports.player)
    checked_port("ports.trainer", ports.trainer)
    checked_timeout(timeout)
    family = socket.getaddrinfo(host, ports.player, type=socket.SOCK_DGRAM)[0][0]
    return (
        Endpoint("player", socket.socket(family, socket.SOCK_DGRAM), (host, ports.player), timeout, log=log),
        Endpoint("trainer", socket.socket(family, socket.SOCK_DGRAM), (host, ports.trainer), timeout, log=log),
    )


class ServerProcess:
    """An rcssserver binary run in a private loopback-only network namespace for the life of a ``with`` block.

    ``with ServerProcess(binary, options) as server:`` gives ``server.ports`` and :meth:`endpoints` (player and
    trainer sockets inside the namespace); leaving the block stops the server's whole process group.

    :param binary: path of the ``rcssserver`` executable.
    :param options: ``server::``/``player::`` options, e.g. ``{"server::synch_mode": True}`` (booleans are written
        ``true``/``false``). Ports and log paths are set here and must not be given.
    :param timeout: seconds to wait for the child to set up and for every receive.
    :raises ServerError: if the binary is missing, the namespace cannot be made (then nothing is started) or the
        server exits at once.
    """

    def __init__(self, binary: str | os.PathLike[str], options: Mapping[str, object], timeout: float = DEFAULT_TIMEOUT):
        self.binary = Path(binary)
        if not self.binary.is_file() or not os.access(self.binary, os.X_OK):
            raise ServerError(f"{str(self.binary)!r} is not an executable file (give the rcssserver binary)")
        reserved = sorted(set(options) & set(_PLACED_OPTIONS))
        if reserved:
            raise ValueError(f"options {reserved} are set by ServerProcess itself (ports and log paths)")
        self.options = dict(options)
        self.timeout = checked_timeout(timeout)
        self.pid = 0
        self.ports = ServerPorts(0, 0, 0)
        self.folder: Path | None = None
        self._sockets: list[socket.socket] = []
        self._temporary: tempfile.TemporaryDirectory[str] | None = None
        self._status: int | None = None

    def __enter__(self) -> ServerProcess:
        self._temporary = tempfile.TemporaryDirectory(prefix="rcssserver-")
        self.folder = Path(self._temporary.name)
        try:
            self._start()
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None) -> None:
        self.stop()

    @property
    def log_file(self) -> Path:
        assert self.folder is not None
        return self.folder / "rcssserver.log"

    def endpoints(self, log: Log | None = None) -> tuple[Endpoint, Endpoint]:
        """``(player, trainer)`` endpoints on the namespace's loopback (call once)."""
        if len(self._sockets) != 2:
            raise RuntimeError("endpoints() is available once, inside the with block")
        player, trainer = self._sockets
        self._sockets = []
        return (
            Endpoint("player", player, ("127.0.0.1", self.ports.player), self.timeout, self.check_running, log),
            Endpoint("trainer", trainer, ("127.0.0.1", self.ports.trainer), self.timeout, self.check_running, log),
        )

    def check_running(self) -> None:
        """:raises ServerError: if the server has exited (with its exit status and the end of its output)."""
        if self._exited():
            raise ServerError(f"rcssserver exited ({_status_text(self._status)}); its output ended with: {self.output_tail()}")

    def missed_cycles(self) -> int:
        """How often the server reported that a client missed a cycle (it waits 1.25 s for a ``(done)``, then steps
        without it: the episodes then played are not the env's)."""
        try:
            return self.log_file.read_text(errors="replace").count("missed a cycle")
        except OSError:
            return 0

    def output_tail(self, lines: int = 5) -> str:
        try:
            text = self.log_file.read_text(errors="replace").strip().splitlines()
        except OSError:
            return "(no output)"
        return " | ".join(text[-lines:]) or "(no output)"

    def stop(self) -> None:
        """Stop the server's process group (SIGTERM, then SIGKILL after :data:`STOP_GRACE` s) and remove its folder."""
        for sock in self._sockets:
            sock.close()
        self._sockets = []
        if self.pid and not self._exited():
            with contextlib.suppress(ProcessLookupError):
                os.killpg(self.pid, signal.SIGTERM)
            deadline = time.monotonic() + STOP_GRACE
            while not self._exited():
                if time.monotonic() > deadline:
                    with contextlib.suppress(ProcessLookupError):
                        os.killpg(self.pid, signal.SIGKILL)
                time.sleep(0.02)
        if self._temporary is not None:
            self._temporary.cleanup()
            self._temporary = None

    def _exited(self) -> bool:
        """Whether the server has exited; when it has, whatever it left in its process group is killed (before the
        server is reaped, so that its process and group id cannot have been given to another process yet)."""
        if self._status is not None:
            return True
        try:
            info = os.waitid(os.P_PID, self.pid, os.WEXITED | os.WNOHANG | os.WNOWAIT)
        except ChildProcessError:
            self._status = -1
            return True
        if info is None:
            return False
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.pid, signal.SIGKILL)
        _, status = os.waitpid(self.pid, 0)
        self._status = os.waitstatus_to_exitcode(status)
        return True

    def _start(self) -> None:
        assert self.folder is not None
        parent_end, child_end = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        log_fd = os.open(self.log_file, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        try:
            pid = os.fork()
            if pid == 0:  # the child: never returns
                parent_end.close()
                _child(child_end, log_fd, str(self.binary), self.options, self.folder)
            self.pid = pid
            child_end.close()
            parent_end.settimeout(self.timeout)
            try:
                message, fds, _, _ = socket.recv_fds(parent_end, 4096, 2)
            except TimeoutError:
                raise ServerError(f"the server's namespace was not set up within {self.timeout:g} s") from None
        finally:
            os.close(log_fd)
            parent_end.close()
            with contextlib.suppress(OSError):
                child_end.close()
        report = json.loads(message.decode() or '{"error": "the child exited before it reported"}')
        if "error" in report:
            for fd in fds:
                os.close(fd)
            raise ServerError(report["error"])
        self._sockets = [socket.socket(fileno=fd) for fd in fds]
        self.ports = ServerPorts(*report["ports"])
        self._wait_until_listening()

    def _wait_until_listening(self) -> None:
        """Wait until the server has bound its player and trainer ports (a message sent before would be lost),
        reading its namespace's UDP table in ``/proc/PID/net/udp``.

        :raises ServerError: if it exits first (bad options, not an rcssserver) or takes longer than the timeout.
        """
        wanted = {self.ports.player, self.ports.trainer}
        deadline = time.monotonic() + self.timeout
        while True:
            self.check_running()
            if wanted <= _bound_udp_ports(self.pid):
                return
            if time.monotonic() > deadline:
                raise ServerError(
                    f"rcssserver did not open its ports within {self.timeout:g} s; its output ended with: {self.output_tail()}"
                )
            time.sleep(0.02)


_PLACED_OPTIONS = (
    "server::port",
    "server::coach_port",
    "server::olcoach_port",
    "server::text_log_dir",
    "server::game_log_dir",
    "server::keepaway_log_dir",
    "server::landmark_file",
)


def _child(channel: socket.socket, log_fd: int, binary: str, options: Mapping[str, object], folder: Path) -> None:
    """In the forked child: make the namespace, report ports and sockets, and become the server (or exit 127)."""
    try:
        os.setsid()
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        _enter_private_network(libc)
        probes = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(3)]
        for probe in probes:  # free ports, held until the client's sockets are bound (so those get others)
            probe.bind(("0.0.0.0", 0))
        ports = [probe.getsockname()[1] for probe in probes]
        client_sockets = [socket.socket(socket.AF_INET, socket.SOCK_DGRAM) for _ in range(2)]
        for sock in client_sockets:
            sock.bind(("127.0.0.1", 0))
        for probe in probes:
            probe.close()
        placed = dict(zip(_PLACED_OPTIONS[:3], ports, strict=True))
        for name in ("server::text_log_dir", "server::game_log_dir", "server::keepaway_log_dir"):
            placed[name] = str(folder)
        placed["server::landmark_file"] = str(folder / "landmark.xml")
        arguments = [binary] + [f"{name}={_option_text(value)}" for name, value in {**options, **placed}.items()]
        socket.send_fds(channel, [json.dumps({"ports": ports}).encode()], [s.fileno() for s in client_sockets])
        channel.close()
        for sock in client_sockets:
            sock.close()
        os.dup2(log_fd, 1)
        os.dup2(log_fd, 2)
        os.chdir(folder)
        environment = {"HOME": str(folder), "PATH": os.environ.get("PATH", "/usr/bin:/bin")}
        os.execve(binary, arguments, environment)
    except BaseException as error:
        with contextlib.suppress(BaseException):
            channel.send(json.dumps({"error": f"{error}"}).encode())
    finally:
        os._exit(127)


def _enter_private_network(libc: ctypes.CDLL) -> None:
    """Move this process into a new network namespace (in a new user namespace unless that is refused to root) and
    bring its loopback interface up.

    :raises OSError: saying why it cannot (then no server may start: it would listen on every address).
    """
    uid, gid = os.getuid(), os.getgid()
    if libc.unshare(_CLONE_NEWUSER | _CLONE_NEWNET) == 0:
        with contextlib.suppress(OSError):  # map ourselves to root in the new namespace (as ``unshare -r``)
            Path("/proc/self/setgroups").write_text("deny")
            Path("/proc/self/uid_map").write_text(f"0 {uid} 1")
            Path("/proc/self/gid_map").write_text(f"0 {gid} 1")
    else:
        first = ctypes.get_errno()
        if libc.unshare(_CLONE_NEWNET) != 0:
            raise OSError(
                first,
                "refusing to start rcssserver: cannot make a private network namespace for it "
                f"(unshare: {os.strerror(first)}), and rcssserver would listen on every address; start a server "
                "yourself where it is safe and connect to it by host and ports instead",
            )
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        request = struct.pack("16sH14x", b"lo", 0)
        flags = struct.unpack("16sH14x", fcntl.ioctl(sock, _SIOCGIFFLAGS, request))[1]
        fcntl.ioctl(sock, _SIOCSIFFLAGS, struct.pack("16sH14x", b"lo", flags | _IFF_UP))
    interfaces = sorted(name for _, name in socket.if_nameindex())
    if interfaces != ["lo"]:
        raise OSError(errno.EPERM, f"the private network namespace holds {interfaces}, not only lo; refusing to start")


def _bound_udp_ports(pid: int) -> set[int]:
    """The local UDP ports bound in the network namespace of process ``pid`` (``/proc/PID/net/udp``, ``udp6``)."""
    ports = set()
    for table in ("udp", "udp6"):
        with contextlib.suppress(OSError):
            for line in Path(f"/proc/{pid}/net/{table}").read_text().splitlines()[1:]:
                ports.add(int(line.split()[1].rsplit(":", 1)[1], 16))
    return ports


def _option_text(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def _status_text(status: int | None) -> str:
    if status is None:
        return "still running"
    if status < 0:
        return f"killed by signal {-status}"
    return f"exit status {status}"
