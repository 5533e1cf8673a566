"""The command line's argument types: options that refuse to be repeated, and the bounded
numbers of ``soilwater path`` (:mod:`soilwater.cli`)."""

import argparse
import math


class Once(argparse.Action):
    """Store an option's value, refusing the option given twice (argparse would keep the
    last silently: ``--out a --out b``)."""

    def __call__(self, parser, namespace, values, option_string=None):
        given = namespace.__dict__.setdefault("_given", set())
        if self.dest in given:
            parser.error(f"{option_string} is given twice: give it once")
        given.add(self.dest)
        setattr(namespace, self.dest, values)


class Parser(argparse.ArgumentParser):
    """An argument parser whose options taking one value refuse to be repeated
    (:class:`Once`); its subcommands' parsers are of this class too."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.register("action", None, Once)
        self.register("action", "store", Once)


def finite(text):
    """A finite float (``--strain``, ``--ocr``): nan and inf are refused."""
    value = float(text)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def ocr(text):
    """An overconsolidation ratio: finite, at most
    :data:`soilwater.material.camclay.MAX_OCR`."""
    from soilwater.material.camclay import MAX_OCR

    value = finite(text)
    if value > MAX_OCR:
        raise argparse.ArgumentTypeError(f"{text} is past {MAX_OCR:g}, no soil's ratio "
                                         "(p'c0 would swamp every other stress)")
    return value


def points(text):
    """Output rows of ``soilwater path``: a whole number from 1 to :data:`MAX_POINTS`."""
    value = int(text)
    if not 1 <= value <= MAX_POINTS:
        raise argparse.ArgumentTypeError(f"{text} must be from 1 to {MAX_POINTS}")
    return value


#: The most output rows of ``soilwater path`` (``--points``).
MAX_POINTS = 1_000_000
