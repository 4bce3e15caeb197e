"""The teacher's console stays readable however often one error repeats."""

import io
import logging

from ur10teach.serving.logs import RepeatLimiter, install


def _logger(stream: io.StringIO, limiter: RepeatLimiter) -> logging.Logger:
    logger = logging.getLogger(f"test.logs.{id(stream)}")
    logger.propagate = False
    handler = logging.StreamHandler(stream)
    handler.addFilter(limiter)
    logger.addHandler(handler)
    return logger


def test_twenty_thousand_tracebacks_become_a_few_lines():
    """A bad widget value used to log a full traceback each time: 20 000 messages wrote 15 MB."""
    stream = io.StringIO()
    logger = _logger(stream, RepeatLimiter(burst=3, window=60.0))
    for k in range(20_000):
        try:
            raise ValueError(f"could not convert string to float: 'x{k}'")
        except ValueError:
            logger.exception("callback failed for client %d", k % 30)
    text = stream.getvalue()
    assert len(text) < 10_000
    assert text.count("Traceback") == 3
    assert "repeating: more like this are counted, not shown" in text


def test_asyncio_reports_of_different_tasks_are_one_kind():
    """asyncio names a different task on each report's second line: still one kind."""
    stream = io.StringIO()
    logger = _logger(stream, RepeatLimiter(burst=2, window=60.0))
    for k in range(500):
        logger.error(f"Task exception was never retrieved\nfuture: <Task finished name='Task-{k}'>")
    assert stream.getvalue().count("Task exception was never retrieved") == 3  # two, and the note


def test_other_kinds_still_show_and_the_count_comes_with_the_next_window():
    stream = io.StringIO()
    limiter = RepeatLimiter(burst=1, window=0.0)  # every record starts a new window
    logger = _logger(stream, limiter)
    logger.warning("refused a websocket: %s", "one")
    logger.warning("refused a websocket: %s", "two")
    assert stream.getvalue().count("refused a websocket") == 2
    limiter.window = 60.0
    logger.warning("an accept failed")
    logger.warning("an accept failed")  # counted: the note
    logger.warning("an accept failed")  # counted silently
    logger.error("something else entirely")
    limiter.window = 0.0
    logger.warning("an accept failed")
    text = stream.getvalue()
    assert "something else entirely" in text
    assert "(and 2 more like this in the minute before, not shown)" in text


def test_each_kind_of_dropped_message_is_shown():
    """Review 2, finding 7: the repeat filter grouped every "dropped a %s" together, so later kinds never showed."""
    stream = io.StringIO()
    logger = _logger(stream, RepeatLimiter(burst=3, window=60.0))
    kinds = ["ShareUrlRequest", "FileTransferStart", "GuiFormDirtyMessage", "malformed SceneNodeClickMessage", "text frame"]
    for kind in kinds:
        logger.warning("dropped a %s from a browser", kind)
    for k in range(10):
        logger.warning("a wrong join code from %s (%d since its last lock-out)", "10.0.0.9", k)
    text = stream.getvalue()
    assert all(f"dropped a {kind} from a browser" in text for kind in kinds)
    assert text.count("a wrong join code from 10.0.0.9") == 4  # three, and the note that more are counted
    # the note is the message as it reads, not its template (issue 30, bug 2)
    assert "%s" not in text and "%d" not in text and "from 10.0.0.9 (3 since its last lock-out) (repeating" in text


def test_the_console_shows_the_websocket_librarys_problems_not_its_news():
    """The teacher's console began with websockets' "server listening on 127.0.0.1:8080" (above the address the app
    prints, which differs when the port was busy) and said "connection open" as students joined."""
    root, library = logging.getLogger(), logging.getLogger("websockets")
    levels, filters = (root.level, library.level), {handler: list(handler.filters) for handler in root.handlers}
    try:
        root.setLevel(logging.INFO)  # (as install() sets it where pytest's own handlers are not there before it)
        install()
        assert logging.getLogger("ur10teach.serving.classroom").isEnabledFor(logging.INFO)
        assert not logging.getLogger("websockets.server").isEnabledFor(logging.INFO)
        assert logging.getLogger("websockets.server").isEnabledFor(logging.WARNING)
    finally:  # (pytest's own handlers lose the limiter install() gave them: it would hide other tests' records)
        root.setLevel(levels[0])
        library.setLevel(levels[1])
        for handler in root.handlers:
            handler.filters[:] = filters.get(handler, [])
