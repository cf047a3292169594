# seaarms: multi-stage build. The builder compiles the release binary (the web page and
# vendored three.js are embedded in it); the runtime stage is a slim Debian with one binary,
# a non-root user and a volume for session records. Configuration is by environment.
ARG BUILDER_IMAGE=rust:1.95-bookworm
ARG RUNTIME_IMAGE=debian:bookworm-slim

FROM ${BUILDER_IMAGE} AS builder
# The default build targets baseline x86-64 (no target-cpu), so the binary runs on any
# x86-64 machine; speed does not need more (docs/speed.md).
WORKDIR /src
COPY . .
RUN cargo build --release --locked --bin seaarms

FROM ${RUNTIME_IMAGE} AS runtime
RUN useradd --system --uid 10001 --user-group --home-dir /var/lib/seaarms --create-home seaarms \
    && mkdir -p /var/lib/seaarms/data \
    && chown -R seaarms:seaarms /var/lib/seaarms
COPY --from=builder /src/target/release/seaarms /usr/local/bin/seaarms
ENV SEAARMS_BIND=0.0.0.0:8080 \
    SEAARMS_DATA_DIR=/var/lib/seaarms/data \
    RUST_LOG=info
VOLUME ["/var/lib/seaarms/data"]
USER 10001:10001
WORKDIR /var/lib/seaarms
EXPOSE 8080
HEALTHCHECK --interval=10s --timeout=3s --start-period=5s --retries=3 \
    CMD ["/usr/local/bin/seaarms", "healthcheck"]
ENTRYPOINT ["/usr/local/bin/seaarms"]
CMD ["serve"]
