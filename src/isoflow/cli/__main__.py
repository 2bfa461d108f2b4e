"""``python -m isoflow.cli``: the ``isoflow`` command."""

from .main import console

if __name__ == "__main__":
    console()
