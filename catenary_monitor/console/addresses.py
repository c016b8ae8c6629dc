"""Every URL a console can be reached at: its bind address, or, bound to all interfaces
(``0.0.0.0``, ``::``), each address of each interface of this PC (Linux: ``SIOCGIFCONF`` and
``/proc/net/if_inet6``; elsewhere the addresses of the host name). Standard library only."""

from __future__ import annotations

import array
import ipaddress
import socket
import struct
import sys

__all__ = ['reachable_urls', 'interface_addresses']

_SIOCGIFCONF = 0x8912
_IFREQ = 40  # struct ifreq on 64-bit Linux: 16 bytes of name, 24 of union


def _ipv4_linux() -> list[str]:
    import fcntl

    buf = array.array('B', bytes(_IFREQ * 256))
    address, _ = buf.buffer_info()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        answer = fcntl.ioctl(sock.fileno(), _SIOCGIFCONF, struct.pack('iL', len(buf), address))
    size = struct.unpack('iL', answer)[0]
    data = buf.tobytes()[:size]
    # each ifreq: the name, then a sockaddr_in whose address is at bytes 4..8
    return [socket.inet_ntoa(data[i + 20 : i + 24]) for i in range(0, size, _IFREQ)]


def _ipv6_linux() -> list[str]:
    try:
        with open('/proc/net/if_inet6', encoding='ascii') as f:
            rows = [line.split()[0] for line in f if line.strip()]
    except OSError:
        return []
    return [str(ipaddress.IPv6Address(bytes.fromhex(h))) for h in rows]


def interface_addresses(family: int = socket.AF_INET) -> list[str]:
    """This PC's addresses of ``family`` (loopback first, then in the kernel's order); IPv6
    link-local ones are left out (a URL would need the interface's name)."""
    found: list[str] = []
    try:
        if not sys.platform.startswith('linux'):
            raise OSError('not Linux')
        found = _ipv4_linux() if family == socket.AF_INET else _ipv6_linux()
    except (OSError, ImportError, struct.error):
        try:
            infos = socket.getaddrinfo(socket.gethostname(), None, family)
        except OSError:
            infos = []
        found = [str(info[4][0]) for info in infos]
    loopback = '127.0.0.1' if family == socket.AF_INET else '::1'
    out = [loopback]
    for text in found:
        ip = ipaddress.ip_address(text)
        if text not in out and not ip.is_link_local and not ip.is_unspecified:
            out.append(text)
    return out


def _url(scheme: str, host: str, port: int) -> str:
    return f'{scheme}://[{host}]:{port}/' if ':' in host else f'{scheme}://{host}:{port}/'


def reachable_urls(scheme: str, bind: str, port: int) -> list[str]:
    """The URLs of a console bound to ``bind``:``port``; this PC's own (loopback) first."""
    if bind in ('0.0.0.0', ''):
        hosts = interface_addresses(socket.AF_INET)
    elif bind == '::':
        hosts = interface_addresses(socket.AF_INET6) + interface_addresses(socket.AF_INET)
    else:
        hosts = [bind.strip('[]')]
    return [_url(scheme, host, port) for host in hosts]
