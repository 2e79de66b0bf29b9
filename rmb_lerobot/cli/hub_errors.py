"""Hugging Face Hub failures as one line: what failed, why, and what to do.

Downloads and uploads go through ``huggingface_hub`` (over ``httpx``), whose errors arrive as
long tracebacks. The command-line tools catch them at their boundary (:func:`is_hub_error`) and
print :func:`describe_hub_error`'s line instead, exiting non-zero.
"""

from __future__ import annotations


class HubUnavailable(RuntimeError):
    """A Hub download or upload failed; the message is the one line to print."""


def is_hub_error(exc: BaseException) -> bool:
    """Whether ``exc`` (or an exception it was raised from) is a Hub or network failure.

    Args:
        exc: The exception caught at the command line's boundary.

    Returns:
        True for ``huggingface_hub``'s HTTP and offline errors and ``httpx``'s transport
        errors, also when another library re-raised them.
    """
    import httpx
    from huggingface_hub import errors

    specific = (errors.HfHubHTTPError, errors.OfflineModeIsEnabled, httpx.HTTPError)
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        if isinstance(current, specific):
            return True
        seen.add(id(current))
        current = current.__cause__ or current.__context__
    return False


def describe_hub_error(what: str, exc: BaseException, *, upload: bool = False) -> str:
    """One line for a failed Hub operation: ``what`` failed, why, and what to do.

    Args:
        what: The operation, e.g. "downloading dataset lerobot/pusht from the Hub".
        exc: The Hub or network error (see :func:`is_hub_error`).
        upload: Whether ``what`` writes to the Hub (the advice then names a write token).

    Returns:
        E.g. "downloading dataset x/y from the Hub failed: repository not found (404); check
        the id, or log in (hf auth login) if it is private or gated".
    """
    import httpx
    from huggingface_hub import errors

    cause = _root_hub_error(exc)
    status = getattr(getattr(cause, "response", None), "status_code", None)
    if isinstance(cause, errors.OfflineModeIsEnabled):
        why = "HF_HUB_OFFLINE is set"
        todo = "unset HF_HUB_OFFLINE to reach the Hub, or use a local copy"
    elif isinstance(cause, errors.RepositoryNotFoundError) or status == 404:
        why = "repository not found (404)"
        todo = "check the id, or log in (hf auth login) if it is private or gated"
    elif isinstance(cause, errors.GatedRepoError):
        why = "the repository is gated"
        todo = "accept its terms on huggingface.co, then log in (hf auth login)"
    elif status in (401, 403):
        why = f"not authorised ({status})"
        todo = (
            "log in with a token that can write to it (hf auth login)"
            if upload
            else "log in (hf auth login) with access to it"
        )
    elif isinstance(cause, httpx.TransportError):
        why = f"the Hub could not be reached ({type(cause).__name__})"
        todo = "check the network connection and proxy settings, then try again"
    else:
        why = (str(cause).strip().splitlines() or [type(cause).__name__])[0]
        if status:
            why = f"{why} (HTTP {status})"
        todo = "try again later; see https://status.huggingface.co"
    return f"{what} failed: {why}; {todo}"


def _root_hub_error(exc: BaseException) -> BaseException:
    """The innermost Hub/network error in ``exc``'s chain (the most specific reason)."""
    import httpx
    from huggingface_hub import errors

    specific = (errors.HfHubHTTPError, errors.OfflineModeIsEnabled, httpx.HTTPError)
    found, seen = exc, set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        if isinstance(current, specific):
            found = current
            if isinstance(current, errors.HfHubHTTPError | errors.OfflineModeIsEnabled):
                return current  # huggingface_hub's own error says the most
        seen.add(id(current))
        current = current.__cause__ or current.__context__
    return found
