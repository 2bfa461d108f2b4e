"""``python -m isoflow``: the ``isoflow`` command."""

from .cli.main import console

if __name__ == "__main__":
    console()
