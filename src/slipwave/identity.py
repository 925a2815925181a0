"""Which test a product belongs to, and what kind of product it is.

Every file slipwave writes about a test carries the test's identity: its ``test_id``
and ``recording_sha256``, the SHA-256 of the acquisition file its recording was read
from (:func:`slipwave.io.read_acquisition`). netCDF files keep them in their global
attributes, with ``product`` naming what the file is (:data:`PRODUCTS`); JSON files
(``fit.json``, a comparison's JSON) keep them as keys. A stage that takes several
files refuses those of different tests (:func:`check_same_test`), and a file that is
not the product an option asks for (:func:`check_product`), before it computes
anything.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable, Mapping, MutableMapping, Sequence
from typing import Any

from slipwave.errors import SlipwaveError
from slipwave.validation import load_schema

PRODUCTS = {
    "recording": "slipwave ingest",
    "events": "slipwave detect --netcdf",
    "simulated recording": "slipwave simulate --fit",
    "contact history": "slipwave simulate --fit --contact",
    "solver steps": "slipwave simulate --fit --steps",
    "kymograph": "slipwave kymograph",
    "behaviour map": "slipwave map assemble",
    "map row": "slipwave map row",
    "quasi-dynamic run": "slipwave simulate-waves",
    "spring-slider record": "slipwave slider-ingest",
    "spring-slider posterior": "slipwave slider-fit",
}
"""The netCDF products, each with the command that writes it."""

IDENTITY_KEYS = ("test_id", "recording_sha256")
"""What names a test's products: its id and its acquisition file's SHA-256."""


@functools.cache
def _test_id_pattern() -> re.Pattern[str]:
    return re.compile(load_schema("tests")["properties"]["test_id"]["pattern"])


def test_id_problem(text: str) -> str | None:
    """What keeps ``text`` from being a test id (the campaign table's pattern), or ``None``.

    A test id names files and pages: letters, digits, ``.``, ``_`` and ``-``, starting
    with a letter or digit.

    Parameters
    ----------
    text
        The id.

    Returns
    -------
    str or None
        The problem in words.

    Examples
    --------
    >>> test_id_problem("hl050") is None
    True
    >>> print(test_id_problem("javascript:alert(1)//"))  # doctest: +ELLIPSIS
    'javascript:alert(1)//' is not a test id (letters, digits, ...)
    """
    if _test_id_pattern().fullmatch(text) is None:
        return (f"{text!r} is not a test id (letters, digits, '.', '_' and '-', from a letter "
                "or digit)")
    return None


def identity_of(attrs: Mapping[Any, Any]) -> dict[str, str]:
    """The test identity a product carries (empty values where it has none).

    Parameters
    ----------
    attrs
        A Dataset's ``attrs`` or a JSON product's content.

    Returns
    -------
    dict
        ``test_id`` and ``recording_sha256``.

    Examples
    --------
    >>> identity_of({"test_id": "hl050", "recording_sha256": "ab12", "units": "N"})
    {'test_id': 'hl050', 'recording_sha256': 'ab12'}
    """
    return {key: str(attrs.get(key, "") or "") for key in IDENTITY_KEYS}


def stamp(attrs: MutableMapping[Any, Any], product: str | None,
          identity: Mapping[Any, Any] | None = None) -> None:
    """Write a product's kind and its test's identity into ``attrs``.

    Parameters
    ----------
    attrs
        A Dataset's ``attrs`` (or a JSON product's content).
    product
        One of :data:`PRODUCTS` (``None`` for a JSON product, named by its keys).
    identity
        The attributes (or content) of the product it is made from, whose
        :func:`identity_of` it takes; ``None``: a product of no one test (a map).

    Examples
    --------
    >>> attrs = {}
    >>> stamp(attrs, "events", {"test_id": "a", "recording_sha256": "ff"})
    >>> attrs
    {'product': 'events', 'test_id': 'a', 'recording_sha256': 'ff'}
    """
    if product is not None:
        if product not in PRODUCTS:
            raise ValueError(f"unknown product {product!r}")
        attrs["product"] = product
    if identity is not None:
        attrs.update(identity_of(identity))


def check_product(attrs: Mapping[Any, Any], product: str, path: object) -> None:
    """Refuse a file that is not the product asked for.

    Parameters
    ----------
    attrs
        The file's global attributes.
    product
        The kind expected (:data:`PRODUCTS`).
    path
        The file, for the message.

    Raises
    ------
    SlipwaveError
        Naming the file, what it is and what was expected, and the command that
        writes the expected product.

    Examples
    --------
    >>> check_product({"product": "events"}, "events", "e.nc")
    >>> check_product({"product": "kymograph"}, "simulated recording", "k.nc")
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipwave.errors.SlipwaveError: k.nc: holds a kymograph, not a simulated recording (...)
    """
    found = str(attrs.get("product", "") or "")
    if found != product:
        what = (f"holds {_noun(found)}" if found
                else "is no product of this slipwave (no 'product' attribute)")
        raise SlipwaveError(f"{path}: {what}, not {_noun(product)} (the product of "
                            f"{PRODUCTS[product]!r})")


def _noun(product: str) -> str:
    return product if product.endswith("s") else f"a {product}"


def check_same_test(products: Iterable[tuple[object, Mapping[Any, Any]]],
                    keys: Sequence[str] = IDENTITY_KEYS) -> None:
    """Refuse files of different tests: their ids or recordings' checksums differ.

    Parameters
    ----------
    products
        (file, its attributes or JSON content), the first the reference. A
        product without an identity is refused too: it cannot be matched.
    keys
        What must agree: the whole identity, or ``("test_id",)`` for a product made
        from no recording (a video's kymograph).

    Raises
    ------
    SlipwaveError
        Naming the two files and their tests.

    Examples
    --------
    >>> a = {"test_id": "hl050", "recording_sha256": "1f"}
    >>> check_same_test([("events.nc", a), ("fit.json", dict(a))])
    >>> check_same_test([("events.nc", a), ("fit.json", {**a, "test_id": "hl075"})])
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    slipwave.errors.SlipwaveError: fit.json is of test 'hl075', events.nc of test 'hl050': ...
    """
    items = list(products)
    if not items:
        return
    first_path, first = items[0][0], identity_of(items[0][1])
    for path, attrs in items:
        identity = identity_of(attrs)
        missing = [key for key in keys if not identity[key]]
        if missing:
            raise SlipwaveError(f"{path}: no {' and no '.join(missing)}: not a product of "
                                "this slipwave, or made before products named their test; "
                                "make it again")
        if identity["test_id"] != first["test_id"]:
            raise SlipwaveError(f"{path} is of test {identity['test_id']!r}, {first_path} of "
                                f"test {first['test_id']!r}: files of different tests cannot "
                                "be combined")
        if "recording_sha256" in keys and identity["recording_sha256"] != first[
                "recording_sha256"]:
            raise SlipwaveError(
                f"{path} and {first_path} are both of test {identity['test_id']!r} but of "
                f"different recordings (SHA-256 {identity['recording_sha256'][:12]}... and "
                f"{first['recording_sha256'][:12]}...): one of them is out of date; make it "
                "again from the current recording")
