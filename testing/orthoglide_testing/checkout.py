"""
The checkout the proving ground runs from: its ``config/`` and working directory.

Named once by whoever knows it: ``test/conftest.py`` (pytest's root
directory), each script and benchmark (its own location). Nothing here
guesses it from where this package lies.
"""

from pathlib import Path

_root = None


class CheckoutError(RuntimeError):
    """No checkout named, or not one of orthoglide_ros."""


def use_checkout(root):
    """Name the checkout (a folder holding ``package.xml`` and ``config/``)."""
    global _root
    root = Path(root).resolve()
    if not (root / 'package.xml').is_file() or not (root / 'config').is_dir():
        raise CheckoutError(f'{root} is not a checkout of orthoglide_ros '
                            '(no package.xml and config/ there)')
    _root = root
    return root


def checkout():
    """Return the checkout named by :func:`use_checkout` (a Path)."""
    if _root is None:
        raise CheckoutError(
            'orthoglide_testing: no checkout named; call '
            'orthoglide_testing.use_checkout(<repository root>) first')
    return _root


def config_file(name):
    """Return the checkout's ``config/<name>`` (``name`` a path: itself)."""
    return checkout() / 'config' / name


def params_file():
    """Return the checkout's ``config/orthoglide.yaml``."""
    return config_file('orthoglide.yaml')
