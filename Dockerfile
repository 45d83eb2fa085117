# The design service with its default data (service/data: curves.h5, emulator.json, surrogate.json).
#   docker build -t balloon-service .
#   docker run --rm -p 8000:8000 -e BALLOON_API_KEY=change-me balloon-service
# Settings are BALLOON_* environment variables (docs/service.md).

# --- build the wheel (sources change often: this stage does not hold the dependencies)
FROM python:3.11-slim AS build
WORKDIR /src
COPY pyproject.toml README.md ./
COPY solver/ solver/
COPY surrogate/ surrogate/
COPY service/ service/
RUN pip wheel --no-cache-dir --no-deps --wheel-dir /wheels .

# --- runtime
FROM python:3.11-slim
ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    MPLBACKEND=Agg

# Dependencies in their own layer, rebuilt only when pyproject.toml changes. Their
# version bounds live in pyproject.toml, hence no pins here.
COPY pyproject.toml /tmp/pyproject.toml
# hadolint ignore=DL3013
RUN python -c "import tomllib; print('\n'.join(tomllib.load(open('/tmp/pyproject.toml', 'rb'))['project']['dependencies']))" > /tmp/requirements.txt \
    && pip install --no-cache-dir -r /tmp/requirements.txt \
    && rm /tmp/requirements.txt /tmp/pyproject.toml

COPY --from=build /wheels /wheels
RUN pip install --no-cache-dir --no-deps /wheels/*.whl && rm -rf /wheels

# The package's own copy of the data (site-packages) is read-only for the service user:
# solve jobs store their curves in a writable copy of the shipped database.
RUN groupadd --gid 10001 balloon && useradd --create-home --uid 10001 --gid 10001 balloon \
    && install -d -o 10001 -g 10001 /home/balloon/data /home/balloon/models
COPY --chown=10001:10001 service/data/curves.h5 /home/balloon/data/curves.h5
USER 10001:10001
WORKDIR /home/balloon
ENV BALLOON_DB_PATH=/home/balloon/data/curves.h5 \
    BALLOON_MODELS_DIR=/home/balloon/models

EXPOSE 8000
HEALTHCHECK --interval=30s --timeout=5s --start-period=30s --retries=3 \
    CMD ["python", "-c", "import sys, urllib.request; sys.exit(urllib.request.urlopen('http://127.0.0.1:8000/v1/health', timeout=4).status != 200)"]
CMD ["balloon", "serve", "--host", "0.0.0.0", "--port", "8000"]
