#!/usr/bin/env python3
"""Write the uncompressed ELF kernel contained in an xz-compressed bzImage.

usage: extract_vmlinux.py VMLINUZ OUT

QEMU can boot the ELF directly (PVH entry), which skips the bzImage decompressor: under TCG that
decompressor alone takes several seconds.
"""
import lzma
import sys


def main(src, dst):
    blob = open(src, "rb").read()
    start = blob.find(b"\xfd7zXZ\x00")  # xz stream magic
    if start < 0:
        sys.exit("%s: no xz stream (not an xz-compressed bzImage)" % src)
    elf = lzma.LZMADecompressor(format=lzma.FORMAT_XZ).decompress(blob[start:])
    if elf[:4] != b"\x7fELF":
        sys.exit("%s: the xz stream is not an ELF kernel" % src)
    with open(dst, "wb") as f:
        f.write(elf)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
