"""The one exception hierarchy of sim_tactile.

Every error the package raises on purpose derives from :class:`SimTactileError`, so a caller
can catch them all at once; the command line turns them into a one-line reason on stderr and
a non-zero exit code.
"""

from __future__ import annotations


class SimTactileError(Exception):
    """Base class of every error raised on purpose by sim_tactile."""


class ConfigError(SimTactileError, ValueError):
    """A parameter, configuration or name is invalid. The message names the parameter, the
    value that was given and what would be valid."""


class UnknownNameError(ConfigError, KeyError):
    """A preset, layout or task name is not known."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class GeometryError(SimTactileError):
    """Generated geometry failed a check (not convex, not watertight, wrong height...)."""


class PhysicsError(SimTactileError):
    """The simulation produced a warning, a NaN, a divergence or a penetration."""


class MissingDependencyError(SimTactileError, ImportError):
    """An optional dependency is missing; the message gives the exact install command."""


class WorkerError(SimTactileError):
    """A worker process running slides died (killed, or out of memory)."""


class StoreError(SimTactileError):
    """A data set's store is missing, of another configuration, incomplete or corrupted."""


class OutputError(SimTactileError):
    """An output file or folder cannot be written (a full disk, a read-only folder)."""


class CacheError(OutputError):
    """The artefact or slide cache cannot be written (a full disk, a read-only folder)."""


class CacheWarning(UserWarning):
    """A cache entry could not be read or failed its checksum: it is made again."""


def os_error_message(exc: OSError, path: object, doing: str = "writing") -> str:
    """One line for an operating-system error on ``path``: a full disk, a read-only folder,
    a missing permission, or the error's own words."""
    import errno

    if exc.errno == errno.ENOSPC:
        return f"no space left on the device {doing} {path}"
    if exc.errno == errno.EDQUOT:
        return f"the disk quota is exceeded {doing} {path}"
    if exc.errno in (errno.EROFS, errno.EACCES, errno.EPERM):
        return f"{path} is read-only or not writable ({exc.strerror})"
    return f"{doing} {path} failed: {exc.strerror or exc}"


class Terminated(KeyboardInterrupt):
    """The process was asked to stop by a signal (SIGTERM: ``kill``, ``timeout``, a batch
    scheduler): handled as Ctrl-C is, so every clean-up that Ctrl-C runs runs for it too."""

    def __init__(self, signum: int = 15) -> None:
        super().__init__(signum)
        self.signum = signum


class NeuronStepWarning(RuntimeWarning):
    """The integration step cannot follow the input: the neuron would fire more than once per
    step (rate above ``1 / dt_s``), or a strongly negative input makes the step unstable."""


def require(name: str, extra: str):
    """Import an optional module or raise with the exact install command."""
    import importlib

    try:
        return importlib.import_module(name)
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise MissingDependencyError(
            f"{name} is needed for this feature: pip install 'sim-tactile[{extra}]'"
        ) from exc


__all__ = [
    "CacheError",
    "CacheWarning",
    "ConfigError",
    "GeometryError",
    "MissingDependencyError",
    "NeuronStepWarning",
    "OutputError",
    "PhysicsError",
    "SimTactileError",
    "StoreError",
    "Terminated",
    "UnknownNameError",
    "WorkerError",
]
