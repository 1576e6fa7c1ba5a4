# The image of docker-compose.yml: the API (`mpm serve --no-worker`) and the workers (`mpm worker`).
FROM python:3.11-slim

ENV PYTHONUNBUFFERED=1 PIP_NO_CACHE_DIR=1 PIP_DISABLE_PIP_VERSION_CHECK=1 \
    MPM_DATA_DIR=/data
RUN useradd --create-home --uid 1000 mpm && mkdir /data && chown mpm /data
WORKDIR /app

COPY pyproject.toml README.md ./
COPY solver solver
COPY core core
COPY worker worker
COPY service service
COPY examples examples
COPY clients/web clients/web
COPY scripts/constraints.txt scripts/constraints.txt
# An editable install: the dashboard (clients/web) and the examples are read beside the
# code, and numba writes its kernel cache beside it (as the mpm user). The compiler stack is
# the one CI tests (scripts/constraints.txt).
RUN pip install -c scripts/constraints.txt -e . && chown -R mpm /app

USER mpm
VOLUME /data
EXPOSE 8000
CMD ["mpm", "serve", "--no-worker", "--host", "0.0.0.0", "--port", "8000"]
