#!/usr/bin/env bash
# Serves a folder of BSVTF tile sets (`btf tiles`) over HTTP with Debian's nginx, in the
# foreground until Ctrl+C, for `btfviewer --stream http://127.0.0.1:PORT/NAME`.
# Usage: tools/serve-tiles.sh DIR [PORT]   (PORT default 8000; listens on 127.0.0.1 only)
set -euo pipefail
if [ $# -lt 1 ] || [ ! -d "$1" ]; then
  sed -n '2,4p' "$0"
  exit 2
fi
root=$(realpath "$1") port=${2:-8000}
nginx=$(command -v nginx || echo /usr/sbin/nginx)
[ -x "$nginx" ] || { echo "serve-tiles.sh: nginx is not installed (apt-get install nginx-light)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
user_line=""
if [ "$(id -u)" = 0 ]; then user_line="user root;"; fi
cat >"$work/nginx.conf" <<CONF
daemon off;
master_process off;
worker_processes 1;
$user_line
pid $work/nginx.pid;
error_log stderr warn;
events { worker_connections 1024; }
http {
  access_log off;
  client_body_temp_path $work/body; proxy_temp_path $work/proxy; fastcgi_temp_path $work/fcgi;
  uwsgi_temp_path $work/uwsgi; scgi_temp_path $work/scgi;
  types { application/octet-stream tile half; text/plain bsvtf; }
  server { listen 127.0.0.1:$port; root $root; }
}
CONF
echo "serve-tiles.sh: http://127.0.0.1:$port/ serves $root (Ctrl+C stops)"
"$nginx" -c "$work/nginx.conf" -p "$work"
