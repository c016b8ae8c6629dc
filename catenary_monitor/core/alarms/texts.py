"""Alarm texts an operator reads in a second: the headline of a status and its detail, and the
response text of its condition.

Every status the core publishes carries a headline as its ``message``, at most
:data:`HEADLINE_LIMIT` characters: what, how much against what is allowed, and what to do
(where is the status's name). The rules' full sentences (every applicable condition joined
with ``'; '``, the held conditions with their clearing rules) go into the ``detail`` value, the
active conditions into ``conditions`` and the condition's response text (cause, consequence,
action: :data:`~catenary_monitor.core.config.responses.DEFAULT_RESPONSES`, or the
``response_texts.<condition>`` parameter) into ``response``.

The headline is the first (most severe) part of the full message, its remarks in parentheses
and its trailing advice dropped until it fits, the count of the other parts after it
(``(+2 more)``) and, where room is left and the part names no action, the condition's short
action (:data:`ACTIONS`). A pure function of the message, so the core and its twin agree.
"""

from __future__ import annotations

import re
from functools import lru_cache
from typing import Mapping, Sequence

from catenary_monitor.core.alarms.latches import CONDITIONS
from catenary_monitor.core.config.responses import DEFAULT_RESPONSES

__all__ = [
    'HEADLINE_LIMIT',
    'ACTIONS',
    'split_parts',
    'headline',
    'response_text',
    'component_condition',
    'status_texts',
    'active_conditions',
    'responses_map',
    'TEXT_KEYS',
]

#: The values every status ends with (:func:`status_texts`).
TEXT_KEYS = ('conditions', 'detail', 'response')

#: The most characters of a status's ``message`` (its headline).
HEADLINE_LIMIT = 100

#: The short action of each condition, appended to a headline that names none.
ACTIONS: dict[str, str] = {
    'uplift': 'reduce load or pay out chain',
    'input': 'check the sensor and its units',
    'anchor_margin': 'watch tide and load',
    'tide_margin': 'pay out chain before high water',
    'load_margin': 'reduce the load',
    'safety_factor': 'reduce the load',
    'time_to_uplift': 'pay out chain or reduce load',
    'inconsistent': 'check cell, chain, anchor',
    'uplift_possible': 'treat as uplift',
    'drag_margin': 'watch the anchor',
    'sensor_error': 'check chain and load cell at once',
    'sensor_warn': 'check the load cell',
    'dragging': 'reduce load, survey the anchor',
    'fatigue': 'plan a chain inspection',
    'channel': 'check the channel',
    'stale': 'check the sensor link',
    'tide': 'check the tide gauge',
    'sensors': 'check gateway, network, power',
    'alarms': 'handle the first-out first',
    'logger': 'free disk space',
    'dock': 'restore the silent sensors',
    'parameters': 'confirm the change',
    'clock': 'check the time source',
    'intake': 'check CPU load and network',
    'fatigue_store': 'check the log directory',
}

# Words that already tell the operator what to do.
_ACTION_WORDS = ('check ', 'reduce ', 'pay out', 'inspect', 'watch ', 'survey', 'free ')


def _outside(text: str, i: int) -> bool:
    """Whether position ``i`` of ``text`` is outside parentheses and quotes."""
    depth = text.count('(', 0, i) - text.count(')', 0, i)
    return depth <= 0 and text.count('"', 0, i) % 2 == 0


def _at(text: str, sep: str) -> list[int]:
    """Where ``sep`` stands outside parentheses and quotes in ``text``."""
    out, i = [], text.find(sep)
    plain = '(' not in text and '"' not in text
    while i >= 0:
        if plain or _outside(text, i):
            out.append(i)
        i = text.find(sep, i + 1)
    return out


def split_parts(message: str) -> list[str]:
    """``message`` split at ``'; '`` outside parentheses and quotes (its conditions' parts)."""
    if '; ' not in message:
        return [message] if message else []
    parts, start = [], 0
    for i in _at(message, '; '):
        parts.append(message[start:i])
        start = i + 2
    parts.append(message[start:])
    return [p for p in parts if p]


_PARENS = re.compile(r'\s*\([^()]*\)')


def _drop_parens(text: str) -> str:
    """``text`` without its parenthesized remarks, spaces tidied."""
    while '(' in text:
        bare = _PARENS.sub('', text)
        if bare == text:
            break
        text = bare
    return ' '.join(text.split()).replace(' :', ':').replace(' ,', ',')


def _shorter(part: str) -> list[str]:
    """The part, then shorter forms of it: without remarks, then cut before each ': ' from
    the right (its advice and explanations), the shortest last."""
    forms = [part]
    bare = _drop_parens(part)
    if bare and bare != part:
        forms.append(bare)
    head = bare or part
    for cut in reversed(_at(head, ': ')):
        if cut >= 12:
            forms.append(head[:cut])
    return forms


def _cut(text: str, limit: int) -> str:
    """``text`` cut at a word boundary to at most ``limit`` characters, ending in ``...``."""
    if len(text) <= limit:
        return text
    head = text[: limit - 3]
    if ' ' in head[limit // 2 :]:
        head = head[: head.rindex(' ')]
    return head.rstrip(' ,:;') + '...'


@lru_cache(maxsize=4096)
def headline(message: str, condition: str = '', limit: int = HEADLINE_LIMIT) -> str:
    """The headline of a status's full ``message`` (at most ``limit`` characters): its first
    part shortened as needed, ``(+n more)`` for the others, and the ``condition``'s short
    action where it fits and the part names none. A message within the limit is its own
    headline (a single part's with the action where it fits)."""
    blind = message.startswith('blind: ')
    action = '' if blind or message == 'OK' else ACTIONS.get(condition, '')
    if len(message) <= limit:
        if not action or _names_action(message) or len(message) + 2 + len(action) > limit:
            return message
        return f'{message}: {action}' if len(split_parts(message)) == 1 else message
    parts = split_parts(message)
    if not parts:
        return _cut(message, limit)
    more = f' (+{len(parts) - 1} more)' if len(parts) > 1 else ''
    shorter = _shorter(parts[0])

    def told(form: str) -> str:  # the form, with the action where it names none and it fits
        text = form + more
        if action and not _names_action(form) and len(text) + 2 + len(action) <= limit:
            return f'{text}: {action}'
        return text

    # Remarks in parentheses may go for the action; the figures (cut at ': ') may not.
    bare = _drop_parens(parts[0])
    for form in [parts[0]] + ([bare] if bare and bare != parts[0] else []):
        if len(told(form)) <= limit and (told(form) != form + more or not action):
            return told(form)
        if _names_action(form) and len(form + more) <= limit:
            return form + more
    for form in shorter:
        if len(form + more) <= limit:
            return told(form)
    return _cut(parts[0], limit - len(more)) + more


def _names_action(text: str) -> bool:
    return any(word in text for word in _ACTION_WORDS)


def response_text(condition: str, configured: Sequence[tuple[str, str]] = ()) -> str:
    """The response text of ``condition`` (``''`` for ``none``/unknown): the configured
    ``response_texts.<condition>`` where given, else the shipped default."""
    for cond, text in configured:
        if cond == condition:
            return text
    return DEFAULT_RESPONSES.get(condition, '')


def component_condition(name: str) -> str:
    """The response condition of a component status (``catenary_monitor: tide`` -> ``tide``;
    the fatigue store's status is ``fatigue_store``, apart from a line's ``fatigue``)."""
    short = name.rsplit(': ', 1)[-1]
    return 'fatigue_store' if short == 'fatigue' else short


def status_texts(
    message: str,
    level_ok: bool,
    condition: str,
    configured: Sequence[tuple[str, str]] = (),
    conditions: str = '',
) -> tuple[str, tuple[tuple[str, str], ...]]:
    """(headline, values) of a status: its ``message`` as the headline and the values
    ``conditions`` (the active ones, comma separated; given for lines), ``detail`` (the full
    message) and ``response`` (``''`` when OK)."""
    if level_ok:
        return headline(message), (
            ('conditions', conditions),
            ('detail', message),
            ('response', ''),
        )
    return headline(message, condition), (
        ('conditions', conditions or condition),
        ('detail', message),
        ('response', response_text(condition, configured)),
    )


def active_conditions(latches: Sequence[bool], stale: bool) -> str:
    """The ``conditions`` value of a line: its active latched conditions (message order),
    then ``stale`` while an input is stale, comma separated (``''``: none)."""
    if not any(latches):
        return 'stale' if stale else ''
    names = [c for c, up in zip(CONDITIONS, latches) if up]
    return ','.join(names + ['stale'] if stale else names)


def responses_map(configured: Sequence[tuple[str, str]] = ()) -> Mapping[str, str]:
    """Every condition's response text (the shipped defaults, the configured ones over them)."""
    out = dict(DEFAULT_RESPONSES)
    out.update(configured)
    return out
