"""The loop of a page without a server or kernel (src/explorer/app/serve/tasks.py): its ``Session`` has a
loop of its own, which the tests run here while they wait, in a thread of its own (the test's thread may
have another loop marked running: Playwright's sync API does so between its calls)."""
from __future__ import annotations

import asyncio
import time
from concurrent.futures import ThreadPoolExecutor

_DRIVER = ThreadPoolExecutor(max_workers=1, thread_name_prefix="explorer-page-loop")


def _drive(session, coro) -> None:
    _DRIVER.submit(session.loop.run_until_complete, coro).result()


def poll(page, seconds: float = 0.01) -> bool:
    """Run the loop of ``page`` (a SectionPage or a Session) for ``seconds``; whether work was pending (a task,
    a timer or a watcher call) when called."""
    session = getattr(page, "session", page)
    pending = session.busy()
    if not session.loop.is_closed():
        _drive(session, asyncio.sleep(seconds))
    return pending


def poll_until(page, done, timeout: float, why: str) -> None:
    """Run the loop of ``page`` (a SectionPage or a Session) until ``done()``; AssertionError ``why`` after
    ``timeout`` seconds."""
    t0 = time.monotonic()
    while not done():
        assert time.monotonic() - t0 < timeout, why
        poll(page)


def settle(page, timeout: float = 240.0) -> None:
    """Run the loop of ``page`` (a SectionPage or a Session) until nothing is pending (TimeoutError after
    ``timeout``)."""
    session = getattr(page, "session", page)

    async def idle():
        while session.busy():
            await asyncio.sleep(0.005)
    _drive(session, asyncio.wait_for(idle(), timeout))
