! Calls the Abaqus shim of docs/guide.md ("Abaqus"), compiled as Abaqus compiles a user
! subroutine (fixed form, INCLUDE 'ABA_PARAM.INC' with implicit REAL*8), the way Abaqus
! calls UMAT: plane strain (NDI 3, NSHR 1, NTENS 4), CMNAME 'CONCRETE' (CHARACTER*80),
! NSTATV = umat_nstatv + 5 (STATEV mode with the five mirrors), the strain path
! [eps, -eps/4, 0] in 25 increments of 1e-5. Each increment is also passed to the module's
! rve_umat directly (another element, its own STATEV): STRESS, DDSDDE and STATEV must be
! the same bits. Prints s_xx, D11, the damage and opening mirrors every fifth increment.
! Usage: driver NSTATV (the scene's umat_nstatv; MESORVE_SCENE_PATH holds concrete.toml).
program driver
  use, intrinsic :: iso_c_binding, only: c_double, c_int, c_size_t
  use rve, only: rve_umat
  implicit none
  external :: umat   ! the shim, called as Abaqus calls it (an implicit interface)
  integer(c_int), parameter :: ntens = 4
  real(c_double) :: stress(ntens, 2), ddsdde(ntens, ntens, 2), stran(ntens), dstran(ntens)
  real(c_double), allocatable :: statev(:, :)
  real(c_double) :: sse, spd, scd, rpl, ddsddt(ntens), drplde(ntens), drpldt, time(2), dtime
  real(c_double) :: temp, dtemp, predef(1), dpred(1), props(6), coords(3), drot(3, 3)
  real(c_double) :: pnewdt(2), celent, dfgrd0(3, 3), dfgrd1(3, 3)
  character(len=80) :: cmname, arg
  integer(c_int) :: nstatv, k
  call get_command_argument(1, arg)
  read (arg, *) nstatv
  nstatv = nstatv + 5
  allocate (statev(nstatv, 2))
  cmname = 'CONCRETE'
  statev = 0; props = 0; stran = 0; time = 0; dtime = 1; stress = 0; ddsdde = 0
  sse = 0; spd = 0; scd = 0; rpl = 0; ddsddt = 0; drplde = 0; drpldt = 0; temp = 0
  dtemp = 0; predef = 0; dpred = 0; coords = 0; drot = 0; celent = 1; dfgrd0 = 0; dfgrd1 = 0
  dstran = [1d-5, -2.5d-6, 0d0, 0d0]
  do k = 1, 25
    pnewdt = 1d36
    call umat(stress(:, 1), statev(:, 1), ddsdde(:, :, 1), sse, spd, scd, rpl, ddsddt, &
        drplde, drpldt, stran, dstran, time, dtime, temp, dtemp, predef, dpred, cmname, &
        3_c_int, 1_c_int, ntens, nstatv, props, 6_c_int, coords, drot, pnewdt(1), celent, &
        dfgrd0, dfgrd1, 1_c_int, 1_c_int, 0_c_int, 0_c_int, 1_c_int, k)
    call rve_umat(stress(:, 2), statev(:, 2), ddsdde(:, :, 2), sse, spd, scd, rpl, ddsddt, &
        drplde, drpldt, stran, dstran, time, dtime, temp, dtemp, predef, dpred, cmname, &
        3_c_int, 1_c_int, ntens, nstatv, props, 6_c_int, coords, drot, pnewdt(2), celent, &
        dfgrd0, dfgrd1, 2_c_int, 1_c_int, 0_c_int, 0_c_int, 1_c_int, k, &
        int(len(cmname), c_size_t))
    if (any(stress(:, 1) /= stress(:, 2)) .or. any(ddsdde(:, :, 1) /= ddsdde(:, :, 2)) .or. &
        any(statev(1:nstatv - 5, 1) /= statev(1:nstatv - 5, 2)) .or. &
        any(statev(nstatv - 1:, 1) /= statev(nstatv - 1:, 2)) .or. pnewdt(1) /= pnewdt(2)) then
      print '(a, i0)', 'abaqus shim: the shim and rve_umat differ at increment ', k
      error stop 1
    end if
    stran = stran + dstran
    time = time + dtime
    if (mod(k, 5) == 0) print '(i3, es12.4, es13.5, es13.5, f8.4, es11.3)', k, stran(1), &
        stress(1, 1), ddsdde(1, 1, 1), statev(nstatv - 1, 1), statev(nstatv, 1)
  end do
  print '(a)', 'abaqus shim: 25 increments, the same bits as rve_umat'
end program driver
