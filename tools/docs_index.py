"""Write docs/index.md, the site's home page: README.md with its links made relative to docs/.

    python tools/docs_index.py            # after editing README.md (tests/test_docs.py checks they agree)
"""

from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def index_text(readme: str) -> str:
    """The README as the site's home page: ``(docs/x.md)`` links become ``(x.md)``."""
    return readme.replace("](docs/", "](")


if __name__ == "__main__":
    (REPO / "docs" / "index.md").write_text(index_text((REPO / "README.md").read_text()))
