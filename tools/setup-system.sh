#!/bin/sh
# System libraries that drjit 1.5 needs and minimal Debian/Ubuntu images lack:
#   - libLLVM >= 17 for the LLVM (JIT) variants: Debian 12's default LLVM 15 aborts inside the JIT.
#     We install libllvm19, which is known to work.
#   - libatomic.so.1: without it `import drjit` fails with a misleading NameError.
# and what the browser test of `mi-brdfs explore` drives (tests/explore/test_browser.py):
#   - Debian's headless Chromium and its ChromeDriver (/usr/bin/chromium, /usr/bin/chromedriver),
#     so that Selenium never downloads a browser; without them that test is skipped.
# Installs them with apt-get when run as root (or with password-less sudo); otherwise it says what
# to install and carries on: mi_brdfs then falls back to the scalar_rgb variant.
set -u

have_llvm() {
  for f in /usr/lib/*-linux-gnu/libLLVM* /usr/lib/llvm-*/lib/libLLVM* /usr/lib64/libLLVM* \
           /usr/local/lib/libLLVM*; do
    [ -e "$f" ] || continue
    v=$(echo "$f" | sed -n 's/.*libLLVM[-.]\([0-9][0-9]*\).*/\1/p; s/.*llvm-\([0-9][0-9]*\)\/lib.*/\1/p' | head -n 1)
    [ -n "$v" ] && [ "$v" -ge 17 ] && return 0
  done
  return 1
}

have_atomic() {
  ldconfig -p 2>/dev/null | grep -q 'libatomic\.so\.1' && return 0
  for f in /usr/lib/*-linux-gnu/libatomic.so.1 /usr/lib64/libatomic.so.1 /usr/lib/libatomic.so.1; do
    [ -e "$f" ] && return 0
  done
  return 1
}

[ "$(uname -s)" = Linux ] || exit 0
lib=""
have_llvm || lib="$lib libllvm19"
have_atomic || lib="$lib libatomic1"
browser=""
[ -x /usr/bin/chromium ] || browser="$browser chromium"
[ -x /usr/bin/chromedriver ] || browser="$browser chromium-driver"
[ -z "$lib$browser" ] && exit 0

# what goes without the packages $1, in words
consequence() {
  case "$1" in
    *llvm*|*atomic*) printf 'mi_brdfs uses the scalar_rgb variant' ;;
    *) printf 'the browser test of mi-brdfs explore is skipped' ;;
  esac
}

if ! command -v apt-get >/dev/null 2>&1; then
  for p in "$lib" "$browser"; do
    [ -n "$p" ] && echo "setup: please install$p with your package manager; until then $(consequence "$p")"
  done
  exit 0
fi
if [ "$(id -u)" -eq 0 ]; then SUDO=""
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then SUDO="sudo -n"
else
  for p in "$lib" "$browser"; do
    [ -n "$p" ] && echo "setup: not root: run 'sudo apt-get install$p'; until then $(consequence "$p")"
  done
  exit 0
fi
export DEBIAN_FRONTEND=noninteractive
# the libraries and the browser apart: a distribution without the browser's packages (Ubuntu's
# chromium is a snap) still gets the libraries
for p in "$lib" "$browser"; do
  [ -n "$p" ] || continue
  echo "setup: installing$p"
  $SUDO apt-get install -y -q --no-install-recommends $p >/dev/null 2>&1 || {
    $SUDO apt-get update -q >/dev/null 2>&1
    $SUDO apt-get install -y -q --no-install-recommends $p >/dev/null || \
      echo "setup: apt-get could not install$p; until then $(consequence "$p")"
  }
done
exit 0
