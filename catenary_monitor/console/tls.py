"""The console's TLS: a server context from a certificate and its key, refused when the
certificate is not valid now.

A certificate past its ``notAfter`` (or before its ``notBefore``) makes every browser warn, and
an operator who learns to click through that warning no longer sees a real attack; so the
console refuses it with one line, unless ``--allow-expired`` (then a loud warning at start).
The dates are read from the certificate's DER (``tbsCertificate.validity``: two UTCTime or
GeneralizedTime values) with the standard library only.
"""

from __future__ import annotations

import base64
import calendar
import os
import re
import ssl
import stat
import time
from typing import Optional

__all__ = ['CertificateError', 'certificate_dates', 'server_context']

_PEM = re.compile(rb'-----BEGIN CERTIFICATE-----(.+?)-----END CERTIFICATE-----', re.S)
#: The largest certificate or key file read (bytes).
MAX_FILE_SIZE = 1024 * 1024


class CertificateError(Exception):
    """A certificate or key that cannot serve: ``str()`` is one line."""


def _tlv(data: bytes, at: int) -> tuple[int, int, int]:
    """(tag, start of the value, end of the value) of the DER element at ``at``."""
    tag, first = data[at], data[at + 1]
    at += 2
    if first & 0x80:
        count = first & 0x7F
        if not 1 <= count <= 4:
            raise ValueError('bad DER length')
        length = int.from_bytes(data[at : at + count], 'big')
        at += count
    else:
        length = first
    if at + length > len(data):
        raise ValueError('DER element past the end')
    return tag, at, at + length


def _time_of(tag: int, text: bytes) -> float:
    """Seconds since the epoch of a DER UTCTime (0x17) or GeneralizedTime (0x18), UTC."""
    value = text.decode('ascii')
    if tag == 0x17:  # YYMMDDHHMMSSZ: 50..99 -> 19xx (RFC 5280)
        year = int(value[:2])
        value = f'{1900 + year if year >= 50 else 2000 + year}{value[2:]}'
    elif tag != 0x18:
        raise ValueError('not a time')
    return float(calendar.timegm(time.strptime(value[:14], '%Y%m%d%H%M%S')))


def certificate_dates(pem: bytes) -> tuple[float, float]:
    """(notBefore, notAfter) of the first certificate in ``pem`` (s since the epoch, UTC).
    Raises ValueError for anything else."""
    match = _PEM.search(pem)
    if match is None:
        raise ValueError('no PEM certificate')
    der = base64.b64decode(b''.join(match.group(1).split()), validate=True)
    _, cert, _ = _tlv(der, 0)  # Certificate ::= SEQUENCE
    _, at, _ = _tlv(der, cert)  # tbsCertificate ::= SEQUENCE
    tag, _, end = _tlv(der, at)
    if tag == 0xA0:  # [0] version
        at = end
    for _ in range(4):  # serialNumber, signature, issuer, then validity
        tag, start, end = _tlv(der, at)
        at = end
    if tag != 0x30:
        raise ValueError('no validity')
    t1, s1, e1 = _tlv(der, start)
    t2, s2, e2 = _tlv(der, e1)
    return _time_of(t1, der[s1:e1]), _time_of(t2, der[s2:e2])


def _read(path: str, what: str) -> bytes:
    """A regular file's bytes (a FIFO or a device is refused, never waited on)."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, 'O_NOCTTY', 0))
    except OSError as err:
        raise CertificateError(f'cannot use the {what} {path}: {err.strerror or err}')
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise CertificateError(f'the {what} {path} is not a regular file')
        if info.st_size > MAX_FILE_SIZE:
            raise CertificateError(f'the {what} {path} is {info.st_size} bytes (at most 1 MiB)')
        return os.read(fd, MAX_FILE_SIZE + 1)
    except OSError as err:
        raise CertificateError(f'cannot use the {what} {path}: {err.strerror or err}')
    finally:
        os.close(fd)


def _day(t: float) -> str:
    return time.strftime('%Y-%m-%d %H:%M:%S UTC', time.gmtime(t))


def server_context(
    cert: str, key: str, *, allow_expired: bool = False, now: Optional[float] = None
) -> tuple[ssl.SSLContext, Optional[str]]:
    """A TLS server context (TLS 1.2 at least) and a warning (None: none). Raises
    :class:`CertificateError` (one line) for files that cannot serve, and for a certificate
    not valid at ``now`` unless ``allow_expired`` (then the warning says so)."""
    pem = _read(cert, 'certificate')
    _read(key, 'key')
    context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    context.minimum_version = ssl.TLSVersion.TLSv1_2
    try:
        context.load_cert_chain(cert, key)
    except (OSError, ssl.SSLError) as err:
        reason = getattr(err, 'strerror', None) or getattr(err, 'reason', None) or err
        raise CertificateError(f'cannot use the certificate {cert} with the key {key}: {reason}')
    try:
        not_before, not_after = certificate_dates(pem)
    except (ValueError, IndexError, UnicodeError, OverflowError):
        raise CertificateError(f'cannot read the validity dates of the certificate {cert}')
    now = time.time() if now is None else now
    problem = None
    if now > not_after:
        problem = f'the certificate {cert} expired on {_day(not_after)}'
    elif now < not_before:
        problem = f'the certificate {cert} is not valid before {_day(not_before)}'
    if problem is None:
        return context, None
    if not allow_expired:
        raise CertificateError(f'{problem}: renew it (or start with --allow-expired)')
    return context, (
        f'WARNING: {problem}; served anyway (--allow-expired): every browser warns, and an '
        'operator used to that warning will not see a real attack. Renew it.'
    )
