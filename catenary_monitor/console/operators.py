"""The console's operators: the token file (``NAME:TOKEN`` a line) and the check of a bearer token.

A token is a shared secret of one operator: it lives in the file only (never on the command
line, in a URL or in a log), travels in ``Authorization: Bearer TOKEN`` and is compared in
constant time. The file: one ``NAME:TOKEN`` per line, ``#`` comments and blank lines allowed;
a name of letters, digits and ``._-`` (at most 64), a token of at least
:data:`MIN_TOKEN_LENGTH` printable characters without spaces; no name and no token twice.
"""

from __future__ import annotations

import hmac
import os
import re
import stat
from typing import Optional

__all__ = ['TokenFileError', 'Operators', 'load_operators', 'MIN_TOKEN_LENGTH']

#: The shortest token accepted (characters): ``openssl rand -hex 16`` gives 32.
MIN_TOKEN_LENGTH = 16
#: The largest token file read (bytes).
MAX_FILE_SIZE = 64 * 1024
_NAME = re.compile(r'[A-Za-z0-9._-]{1,64}')
_TOKEN = re.compile(r'[\x21-\x7e]+')


class TokenFileError(Exception):
    """A token file that cannot be used: ``str()`` is one line (never a token)."""


class Operators:
    """The operators of a token file: :meth:`who` names the one a bearer token belongs to."""

    def __init__(self, tokens: dict[str, str]) -> None:
        self._tokens = [(name, token.encode('ascii')) for name, token in tokens.items()]

    @property
    def names(self) -> list[str]:
        return [name for name, _ in self._tokens]

    def who(self, authorization: Optional[str]) -> Optional[str]:
        """The operator whose token ``authorization`` (the header's value, ``Bearer TOKEN``)
        carries, or None. Every token is compared, in constant time."""
        if not authorization:
            return None
        scheme, _, token = authorization.strip().partition(' ')
        if scheme.lower() != 'bearer' or not token:
            return None
        given = token.strip().encode('ascii', 'replace')
        found = None
        for name, secret in self._tokens:
            if hmac.compare_digest(given, secret):
                found = name
        return found


def load_operators(path: str) -> tuple[Operators, Optional[str]]:
    """The operators of the token file ``path`` and a warning (None: none): a file that
    others than its owner may read. Raises :class:`TokenFileError` naming the line."""
    try:
        # Opened without waiting (a FIFO would block a plain open until a writer comes),
        # then refused unless a regular file.
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, 'O_NOCTTY', 0))
        try:
            info = os.fstat(fd)
            if not stat.S_ISREG(info.st_mode):
                raise TokenFileError(f'the token file {path} is not a regular file')
            if info.st_size > MAX_FILE_SIZE:
                raise TokenFileError(
                    f'{path}: {info.st_size} bytes (a token file is at most 64 KiB)'
                )
            text = os.read(fd, MAX_FILE_SIZE + 1).decode('utf-8')
        finally:
            os.close(fd)
    except OSError as err:
        raise TokenFileError(f'cannot read the token file {path}: {err.strerror or err}')
    except UnicodeDecodeError:
        raise TokenFileError(f'{path}: not UTF-8 text')
    tokens: dict[str, str] = {}
    where: dict[str, int] = {}
    seen: dict[str, int] = {}
    for number, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line.startswith('#'):
            continue
        name, colon, token = (part.strip() for part in line.partition(':'))
        if not colon or not _NAME.fullmatch(name):
            raise TokenFileError(
                f'{path}:{number}: expected NAME:TOKEN (a name of letters, digits and ._-)'
            )
        if not _TOKEN.fullmatch(token) or len(token) < MIN_TOKEN_LENGTH:
            raise TokenFileError(
                f'{path}:{number}: the token of {name!r} must be at least {MIN_TOKEN_LENGTH} '
                'printable characters without spaces (openssl rand -hex 16)'
            )
        if name in where:
            raise TokenFileError(f'{path}:{number}: {name!r} again (line {where[name]})')
        if token in seen:
            raise TokenFileError(f'{path}:{number}: the same token as line {seen[token]}')
        tokens[name], where[name], seen[token] = token, number, number
    if not tokens:
        raise TokenFileError(f'{path}: no NAME:TOKEN line')
    warning = None
    if info.st_mode & (stat.S_IRWXG | stat.S_IRWXO):
        warning = f'{path} may be read by other users than its owner (chmod 600 {path})'
    return Operators(tokens), warning
