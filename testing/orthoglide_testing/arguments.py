"""The command lines of the scripts and benchmarks: one parser maker."""

import argparse


def script_parser(doc, *options):
    """
    Return a script's parser: ``doc``'s first paragraph, then ``options``.

    Each option a ``(flag, default, help)`` row: its type is the
    default's (int, float or str), the default is said after the help.
    """
    parser = argparse.ArgumentParser(
        description=doc.strip().split('\n\n')[0])
    for flag, default, text in options:
        parser.add_argument(flag, type=type(default), default=default,
                            help=f'{text} (default %(default)s)')
    return parser


def seeds(text):
    """
    Parse a ``--seeds`` option: ``0-9`` or ``0,3,5`` into a list of seeds.

    >>> seeds('2-4'), seeds('0,3,5')
    ([2, 3, 4], [0, 3, 5])
    """
    if '-' in text:
        first, last = (int(v) for v in text.split('-'))
        return list(range(first, last + 1))
    return [int(v) for v in text.split(',')]
