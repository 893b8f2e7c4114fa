! statev_restart.f90 -- a restart through STATEV written as text: the library's UMAT
! called as Abaqus calls a user material (`CALL UMAT(...)`, resolved to `umat_`; no
! `use rve`), with NSTATV = `rve info SCENE --json`'s umat_nstatv + 3, so the RVE's
! committed state lives in STATEV(1:umat_nstatv) (STATEV mode) and STATEV(umat_nstatv+1:+3)
! receive the point id, the RVE Newton iterations and the sub-steps.
!
! The path is the paper's cycle of scenes/paper_rve_cycle.toml (section 5.2.2): tension
! to eps_xx = 2.3e-4 in 20 increments (past the peak), unloading and compression to
! -4.5e-4 in 40, computed as `rve` computes a scene's path. Each increment has two calls
! (a first iteration at 99 % of the strain step, then the step's end), each from the
! start-of-increment STATEV; the values of the last call are kept (the host protocol of
! Abaqus/Standard and CalculiX). KSTEP 1, KINC and TIME continue across the restart.
!
! MODE whole   all 60 increments; the answers to OUT.
! MODE first   increments 1-30; the answers to OUT, then STATEV(1:NSTATV+3) to FILE, one
!              value a line with ES25.17 (18 significant digits; the state values are
!              integers below 2^48, at most 15 digits, so the text is exact). The file is
!              read back into a zeroed array here and compared bit for bit.
! MODE second  STATEV read from FILE into a fresh array of a new process (the library's
!              table knows nothing of the first half), increments 31-60; the answers to
!              OUT. Then (unless FILE holds zeros) the same state written with too few
!              digits (ES15.7) must be refused: PNEWDT < 1, STRESS untouched.
! The answers are one line per increment: KINC, then the bits (Z16) of STRESS(1:3),
! DDSDDE(1:3, 1:3) and PNEWDT, then RVE iterations and sub-steps. The test script checks
! that `first` then `second` give the lines of `whole`, bit for bit.
!
! Usage: MESORVE_SCENE_PATH=scenes statev_restart NSTATV MODE FILE OUT
! Exit status 0 when every check passed.
program statev_restart
  use, intrinsic :: iso_fortran_env, only: error_unit, int64, real64
  implicit none

  interface
    subroutine umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, &
        stran, dstran, time, dtime, temp, dtemp, predef, dpred, cmname, ndi, nshr, ntens, &
        nstatv, props, nprops, coords, drot, pnewdt, celent, dfgrd0, dfgrd1, noel, npt, &
        layer, kspt, kstep, kinc)
      import :: real64
      character(len=80), intent(in) :: cmname
      integer, intent(in) :: ndi, nshr, ntens, nstatv, nprops, noel, npt, layer, kspt, &
          kstep, kinc
      real(real64), intent(inout) :: stress(ntens), statev(nstatv), &
          ddsdde(ntens, ntens), sse, spd, scd, rpl, ddsddt(ntens), drplde(ntens), drpldt, &
          pnewdt
      real(real64), intent(in) :: stran(ntens), dstran(ntens), time(2), dtime, temp, &
          dtemp, predef(1), dpred(1), props(nprops), coords(3), drot(3, 3), celent, &
          dfgrd0(3, 3), dfgrd1(3, 3)
    end subroutine umat
  end interface

  integer, parameter :: rows = 60, half = 30, mirrors = 3
  character(len=*), parameter :: state_format = '(es25.17)', lossy_format = '(es15.7)'
  integer :: checks = 0, failures = 0, nstatv, n, ios
  real(real64) :: path(3, rows)
  real(real64), allocatable :: statev(:)
  character(len=4096) :: arg, mode, file, out

  if (command_argument_count() /= 4) then
    write (error_unit, '(a)') 'usage: statev_restart NSTATV whole|first|second FILE OUT'
    stop 2
  end if
  call get_command_argument(1, arg)
  read (arg, *, iostat=ios) nstatv
  if (ios /= 0 .or. nstatv < 4) then
    write (error_unit, '(a)') 'statev_restart: NSTATV must be a count (rve info --json)'
    stop 2
  end if
  call get_command_argument(2, mode)
  call get_command_argument(3, file)
  call get_command_argument(4, out)
  n = nstatv + mirrors
  allocate (statev(n))
  call paper_cycle(path)

  select case (trim(mode))
  case ('whole')
    statev = 0
    call run(1, rows, statev, trim(out))
  case ('first')
    statev = 0
    call run(1, half, statev, trim(out))
    call save_statev(trim(file), statev)
    call check_round_trip(trim(file), statev)
  case ('second')
    call load_statev(trim(file), statev)
    call run(half + 1, rows, statev, trim(out))
    call lossy_text_is_refused(trim(file))
  case default
    write (error_unit, '(2a)') 'statev_restart: unknown mode ', trim(mode)
    stop 2
  end select
  write (*, '(3a,i0,a,i0,a)') 'statev_restart ', trim(mode), ': ', checks, ' checks, ', &
      failures, ' failed'
  deallocate (statev)
  if (failures > 0) stop 1

contains

  subroutine expect(ok, what)
    logical, intent(in) :: ok
    character(len=*), intent(in) :: what
    checks = checks + 1
    if (.not. ok) then
      failures = failures + 1
      write (error_unit, '(a)') 'FAILED: ' // what
    end if
  end subroutine expect

  logical function same_bits(a, b)
    real(real64), intent(in) :: a(:), b(:)
    same_bits = size(a) == size(b)
    if (same_bits) same_bits = all(transfer(a, 0_int64, size(a)) == transfer(b, 0_int64, size(b)))
  end function same_bits

  ! The strains of scenes/paper_rve_cycle.toml's [[path]], as `rve` computes them: equal
  ! steps within a segment, the segment's end exact.
  subroutine paper_cycle(p)
    real(real64), intent(out) :: p(3, rows)
    real(real64) :: from(3), to(3), t
    integer :: seg, k, m, row
    integer, parameter :: steps(2) = [20, 40]
    real(real64), parameter :: ends(3, 2) = reshape([2.3e-4_real64, 0.0_real64, 0.0_real64, &
        -4.5e-4_real64, 0.0_real64, 0.0_real64], [3, 2])
    from = 0; row = 0
    do seg = 1, 2
      to = ends(:, seg); m = steps(seg)
      do k = 1, m
        row = row + 1
        t = real(k, real64) / real(m, real64)
        if (k == m) then
          p(:, row) = to
        else
          p(:, row) = from + t * (to - from)
        end if
      end do
      from = to
    end do
  end subroutine paper_cycle

  ! DSTRAN with STRAN + DSTRAN == target bit for bit (target - stran can round).
  function step_to(stran, target) result(d)
    real(real64), intent(in) :: stran(3), target(3)
    real(real64) :: d(3)
    integer :: i, k
    d = target - stran
    do i = 1, 3
      do k = 1, 8
        if (same_bits([stran(i) + d(i)], [target(i)])) exit
        if (stran(i) + d(i) < target(i)) then
          d(i) = nearest(d(i), 1.0_real64)
        else
          d(i) = nearest(d(i), -1.0_real64)
        end if
      end do
    end do
  end function step_to

  ! One UMAT call of increment kinc (plane stress, NTENS 3, NOEL 1, NPT 1, KSTEP 1).
  subroutine call_umat(kinc, stran, target, stress, ddsdde, sv, pnewdt)
    integer, intent(in) :: kinc
    real(real64), intent(in) :: stran(3), target(3)
    real(real64), intent(inout) :: stress(3), ddsdde(3, 3), sv(:), pnewdt
    character(len=80) :: cmname
    real(real64) :: sse, spd, scd, rpl, ddsddt(3), drplde(3), drpldt, predef(1), dpred(1)
    real(real64) :: coords(3), drot(3, 3), time(2), dtime, props(1)
    integer :: k
    cmname = 'PAPER_RVE'
    sse = 0; spd = 0; scd = 0; rpl = 0; ddsddt = 0; drplde = 0; drpldt = 0
    predef = 0; dpred = 0; coords = [1.0_real64, 2.0_real64, 0.0_real64]; props = 0
    drot = 0
    do k = 1, 3
      drot(k, k) = 1
    end do
    dtime = 1.0_real64 / rows
    time = (kinc - 1) * dtime
    pnewdt = 1e36_real64
    call umat(stress, sv, ddsdde, sse, spd, scd, rpl, ddsddt, drplde, drpldt, stran, &
        step_to(stran, target), time, dtime, 20.0_real64, 0.0_real64, predef, dpred, &
        cmname, 2, 1, 3, size(sv), props, 0, coords, drot, pnewdt, 1.0_real64, drot, drot, &
        1, 1, 0, 0, 1, kinc)
  end subroutine call_umat

  ! Increments first..last as the host runs them; one line of answers per increment.
  subroutine run(first, last, sv, path_out)
    integer, intent(in) :: first, last
    real(real64), intent(inout) :: sv(:)
    character(len=*), intent(in) :: path_out
    real(real64) :: work(size(sv)), stran(3), near(3), stress(3), ddsdde(3, 3), pnewdt
    real(real64) :: peak
    integer :: u, kinc, c
    logical :: solved
    open (newunit=u, file=path_out, status='replace', action='write')
    solved = .true.; peak = 0
    do kinc = first, last
      stran = 0
      if (kinc > 1) stran = path(:, kinc - 1)
      near = stran + 0.99_real64 * (path(:, kinc) - stran)
      do c = 1, 2
        work = sv                      ! the start-of-increment values at every call
        stress = 7
        if (c == 1) call call_umat(kinc, stran, near, stress, ddsdde, work, pnewdt)
        if (c == 2) call call_umat(kinc, stran, path(:, kinc), stress, ddsdde, work, pnewdt)
        ! Success leaves PNEWDT at 1e36 (or asks 0.5 when the answer depends on the
        ! step's size) and writes the state tag to STATEV(1).
        solved = solved .and. pnewdt >= 0.5_real64 .and. work(1) > 0
      end do
      sv = work                        ! converged: keep the last call's values
      peak = max(peak, stress(1))
      write (u, '(i0,13(1x,z16.16),2(1x,i0))') kinc, transfer(stress, 0_int64, 3), &
          transfer(ddsdde, 0_int64, 9), transfer(pnewdt, 0_int64), &
          nint(sv(nstatv + 2)), nint(sv(nstatv + 3))
    end do
    close (u)
    call expect(solved, 'every call of increments answered')
    write (*, '(a,i0,a,i0,a,f8.5,a,f9.5,a,i0)') 'increments ', first, '-', last, &
        ': max s_xx ', peak, ' MPa, last s_xx ', stress(1), ' MPa, STATEV entries in use ', &
        last_used(sv)
  end subroutine run

  integer function last_used(sv)
    real(real64), intent(in) :: sv(:)
    integer :: k
    last_used = 0
    do k = 1, nstatv
      if (abs(sv(k)) > 0) last_used = k
    end do
  end function last_used

  subroutine save_statev(path_file, sv)
    character(len=*), intent(in) :: path_file
    real(real64), intent(in) :: sv(:)
    integer :: u, k
    open (newunit=u, file=path_file, status='replace', action='write')
    write (u, '(i0)') size(sv)
    do k = 1, size(sv)
      write (u, state_format) sv(k)
    end do
    close (u)
  end subroutine save_statev

  subroutine load_statev(path_file, sv)
    character(len=*), intent(in) :: path_file
    real(real64), intent(out) :: sv(:)
    integer :: u, k, count, ios
    open (newunit=u, file=path_file, status='old', action='read', iostat=ios)
    if (ios /= 0) then
      write (error_unit, '(2a)') 'cannot open ', path_file
      stop 1
    end if
    read (u, *) count
    if (count /= size(sv)) then
      write (error_unit, '(a,i0,a,i0)') 'the file holds ', count, ' values, NSTATV + 3 = ', &
          size(sv)
      stop 1
    end if
    do k = 1, size(sv)
      read (u, state_format, iostat=ios) sv(k)
      if (ios /= 0) then
        write (error_unit, '(a,i0)') 'cannot read STATEV value ', k
        stop 1
      end if
    end do
    close (u)
  end subroutine load_statev

  ! The file read back into a zeroed array gives the values bit for bit.
  subroutine check_round_trip(path_file, sv)
    character(len=*), intent(in) :: path_file
    real(real64), intent(in) :: sv(:)
    real(real64) :: back(size(sv))
    back = 0
    call load_statev(path_file, back)
    call expect(same_bits(back, sv), 'STATEV through ' // state_format // ' text: bit for bit')
    call expect(same_bits(sv(:nstatv), aint(sv(:nstatv))) .and. all(sv(:nstatv) >= 0) .and. &
        all(sv(:nstatv) < 2.0_real64**48), 'STATEV(1:NSTATV) are integers in [0, 2^48)')
    write (*, '(3a,i0,a)') 'STATEV written with ', state_format, ' and read back: ', &
        size(sv), ' values bit-identical'
  end subroutine check_round_trip

  ! The same state through a format with 8 significant digits: refused, STRESS untouched.
  subroutine lossy_text_is_refused(path_file)
    character(len=*), intent(in) :: path_file
    real(real64) :: sv(n), stress(3), ddsdde(3, 3), pnewdt, stran(3)
    character(len=15) :: text
    integer :: k, changed
    call load_statev(path_file, sv)
    if (last_used(sv) == 0) then
      write (*, '(a)') 'STATEV from the file is all zeros (a virgin RVE): no ES15.7 check'
      return
    end if
    changed = 0
    do k = 1, nstatv
      write (text, lossy_format) sv(k)
      read (text, lossy_format) sv(k)
    end do
    call load_statev(path_file, statev)
    do k = 1, nstatv
      if (.not. same_bits([sv(k)], [statev(k)])) changed = changed + 1
    end do
    stress = 7
    stran = path(:, half)
    call call_umat(half + 1, stran, path(:, half + 1), stress, ddsdde, sv, pnewdt)
    call expect(changed > 0, 'ES15.7 changes some STATEV values')
    call expect(pnewdt < 1, 'STATEV through ES15.7: refused with PNEWDT < 1')
    call expect(same_bits(stress, [7.0_real64, 7.0_real64, 7.0_real64]), 'STATEV through ES15.7: STRESS untouched')
    write (*, '(a,i0,a,es9.2)') 'STATEV through ES15.7 (', changed, &
        ' values changed): refused, PNEWDT = ', pnewdt
  end subroutine lossy_text_is_refused

end program statev_restart
