"""Errors raised by soilwater: one clear line naming the parameter and the fix."""


class SoilwaterError(Exception):
    """Base class of every error soilwater raises on purpose."""


class InputError(SoilwaterError, ValueError):
    """Bad input: the message names the parameter, its value and the fix."""


class ConvergenceError(SoilwaterError, RuntimeError):
    """A local or global iteration did not converge; the message says where."""


def require(condition, message):
    """Raise :class:`InputError` with ``message`` unless ``condition`` holds."""
    if not condition:
        raise InputError(message)
