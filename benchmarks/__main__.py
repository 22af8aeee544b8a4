"""`make bench`: run every benchmark and print its table."""

from benchmarks import (
    bench_cli,
    bench_command,
    bench_dashboard,
    bench_endpoint,
    bench_hsmm,
    bench_optim,
    bench_placements,
    bench_plan,
    bench_ray,
    bench_reorient,
    bench_sim,
    bench_stl,
    bench_tracking,
)


def main() -> None:
    bench_cli.main()
    bench_stl.main()
    bench_hsmm.main()
    bench_endpoint.main()
    bench_sim.main()
    bench_command.main([])
    bench_ray.main([])
    bench_dashboard.main([])
    bench_optim.main([])
    bench_plan.main([])
    bench_tracking.main([])
    bench_placements.main([])
    bench_reorient.main(["--demonstrated-yaws"])
    bench_reorient.main([])


if __name__ == "__main__":
    main()
