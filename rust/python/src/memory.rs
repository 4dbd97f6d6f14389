//! Memory that goes back to the system. glibc's malloc raises its mmap threshold after
//! a large block is freed (up to 32 MB), so later day tiles (17.5 MB) come from the
//! thread arenas and stay there when freed: a streamed run through an atlas with a
//! budget of 0 held 250 MB more than the tiles it used. A fixed 1 MiB threshold serves
//! every large block by mmap and returns it on free. A user's `MALLOC_MMAP_THRESHOLD_`
//! (glibc's own setting) is left as it is.

/// Fixes glibc's mmap threshold at 1 MiB unless the environment sets it.
pub fn return_large_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_none() {
        // SAFETY: mallopt only changes an allocator parameter; it is safe to call at
        // any time (it takes the arena locks itself).
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, 1 << 20);
        }
    }
}
