! umat_driver.f90 -- drives the library's UMAT exactly as Abaqus calls a user material:
! `CALL UMAT(...)` with the 37 Abaqus arguments and CMNAME a CHARACTER*80 (gfortran
! appends its hidden length), resolved to the library's `umat_`. No `use rve`: a host
! needs nothing from mesorve but the library.
!
!  1. The paper's tension-compression cycle (scenes/paper_rve_cycle.toml, NTENS = 3,
!     plane stress) increment by increment: each increment a first iteration at half the
!     strain step, then the converged strain; increments 10, 30 and 50 first try a double
!     step and are cut back (same KINC, half the DTIME); STATEV is reset to zero before
!     every call, as CalculiX does. Stress, DDSDDE (= the C tangent transposed), RVE
!     iterations and sub-steps (STATEV(2:3)) must equal the C driver's CSV bit for bit.
!  2. NTENS = 4 and 6 on a plane-strain scene (calculix_examples/concrete.toml): one
!     answer in both layouts, s_33 = s_zz and the documented out-of-plane entries.
!  3. Error paths: a missing scene, NTENS = 5, a plane-stress scene under NTENS = 6 and an
!     out-of-plane shear strain each give PNEWDT < 1 with STRESS untouched.
!
! Usage: MESORVE_SCENE_PATH=scenes:calculix_examples umat_driver C_DRIVER.csv
! Exit status 0 when every check passed.
program umat_driver
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

  integer, parameter :: rows = 60, cols = 20
  integer :: checks = 0, failures = 0
  character(len=4096) :: csv
  real(real64) :: ref(cols, rows)

  if (command_argument_count() < 1) then
    write (error_unit, '(a)') 'usage: umat_driver C_DRIVER.csv'
    stop 2
  end if
  call get_command_argument(1, csv)
  call read_reference(trim(csv))
  call paper_cycle()
  call layouts()
  call errors()
  write (*, '(a,i0,a,i0,a)') 'umat_driver: ', checks, ' checks, ', failures, ' failed'
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

  ! Every entry still holds the 7 it was given before the call.
  logical function untouched(a)
    real(real64), intent(in) :: a(:)
    untouched = maxval(abs(a - 7)) < tiny(1.0_real64)
  end function untouched

  logical function same_bits(a, b)
    real(real64), intent(in) :: a, b
    same_bits = transfer(a, 0_int64) == transfer(b, 0_int64)
  end function same_bits

  ! The C driver's CSV (header, then `rows` rows of `cols` numbers written with %.17g).
  subroutine read_reference(path)
    character(len=*), intent(in) :: path
    integer :: u, ios, k
    character(len=1024) :: header
    open (newunit=u, file=path, status='old', action='read', iostat=ios)
    if (ios /= 0) then
      write (error_unit, '(2a)') 'cannot open ', path
      stop 1
    end if
    read (u, '(a)') header
    do k = 1, rows
      read (u, *, iostat=ios) ref(:, k)
      if (ios /= 0) then
        write (error_unit, '(a,i0)') 'cannot read row ', k
        stop 1
      end if
    end do
    close (u)
  end subroutine read_reference

  ! One UMAT call with the arguments the RVE does not use set to what a host would pass.
  subroutine call_umat(name, ntens, stran, dstran, time, dtime, props, noel, kinc, stress, &
      ddsdde, statev, pnewdt)
    character(len=*), intent(in) :: name
    integer, intent(in) :: ntens, noel, kinc
    real(real64), intent(in) :: stran(ntens), dstran(ntens), time(2), dtime, props(:)
    real(real64), intent(inout) :: stress(ntens), ddsdde(ntens, ntens), statev(3), pnewdt
    character(len=80) :: cmname
    real(real64) :: sse, spd, scd, rpl, ddsddt(6), drplde(6), drpldt, predef(1), dpred(1)
    real(real64) :: coords(3), drot(3, 3), dfgrd(3, 3)
    integer :: ndi, nshr, k
    cmname = name
    sse = 0; spd = 0; scd = 0; rpl = 0; ddsddt = 0; drplde = 0; drpldt = 0
    predef = 0; dpred = 0; coords = [1.0_real64, 2.0_real64, 0.0_real64]
    drot = 0; dfgrd = 0
    do k = 1, 3
      drot(k, k) = 1; dfgrd(k, k) = 1
    end do
    ndi = 3; nshr = ntens - 3
    if (ntens == 3) ndi = 2
    if (ntens == 3) nshr = 1
    call umat(stress, statev, ddsdde, sse, spd, scd, rpl, ddsddt(:ntens), drplde(:ntens), &
        drpldt, stran, dstran, time, dtime, 20.0_real64, 0.0_real64, predef, dpred, cmname, &
        ndi, nshr, ntens, 3, props, size(props), coords, drot, pnewdt, 1.0_real64, dfgrd, &
        dfgrd, noel, 1, 0, 0, 1, kinc)
  end subroutine call_umat

  ! DSTRAN with stran + dstran == strain bit for bit (eps - stran can round).
  function step_to(stran, strain) result(d)
    real(real64), intent(in) :: stran(:), strain(:)
    real(real64) :: d(size(strain))
    integer :: i, k
    d = strain - stran
    do i = 1, size(d)
      do k = 1, 8
        if (same_bits(stran(i) + d(i), strain(i))) exit
        if (stran(i) + d(i) < strain(i)) then
          d(i) = nearest(d(i), 1.0_real64)
        else
          d(i) = nearest(d(i), -1.0_real64)
        end if
      end do
    end do
  end function step_to

  ! Part 1: the paper's cycle, as Abaqus would run it with cut-backs; against the C driver.
  subroutine paper_cycle()
    real(real64) :: stran(3), eps(3), half(3), big(3), stress(3), ddsdde(3, 3), statev(3)
    real(real64) :: pnewdt, time(2), dt, props(0)
    integer :: kinc, i, j, asked
    logical :: ok_stress, ok_tangent, ok_counts, ok_id
    stran = 0; time = 0; dt = 1.0_real64 / rows; asked = 0
    ok_stress = .true.; ok_tangent = .true.; ok_counts = .true.; ok_id = .true.
    do kinc = 1, rows
      eps = ref(2:4, kinc)
      pnewdt = 1e36_real64
      if (mod(kinc, 20) == 10) then
        ! A first attempt at twice the step, then the host cuts back (same KINC).
        big = stran + 2 * (eps - stran)
        statev = 0
        call call_umat('PAPER_RVE_CYCLE', 3, stran, big - stran, time, 2 * dt, props, 1, &
            kinc, stress, ddsdde, statev, pnewdt)
      end if
      half = stran + 0.5_real64 * (eps - stran)
      statev = 0
      call call_umat('PAPER_RVE_CYCLE', 3, stran, half - stran, time, dt, props, 1, kinc, &
          stress, ddsdde, statev, pnewdt)
      statev = 0
      call call_umat('PAPER_RVE_CYCLE', 3, stran, step_to(stran, eps), time, dt, props, 1, &
          kinc, stress, ddsdde, statev, pnewdt)
      do i = 1, 3
        ok_stress = ok_stress .and. same_bits(stress(i), ref(4 + i, kinc))
        do j = 1, 3
          ok_tangent = ok_tangent .and. same_bits(ddsdde(i, j), ref(7 + 3 * (i - 1) + j, kinc))
        end do
      end do
      ok_counts = ok_counts .and. same_bits(statev(2), ref(17, kinc)) .and. &
          same_bits(statev(3), ref(18, kinc))
      ! PNEWDT stays untouched, but where the RVE's answer depends on the step
      ! (solver.step_check: an increment's two halves reach another equilibrium), which
      ! asks for half the step and changes no answer.
      if (same_bits(pnewdt, 0.5_real64)) asked = asked + 1
      ok_id = ok_id .and. statev(1) >= 1 .and. (pnewdt > 1 .or. same_bits(pnewdt, 0.5_real64))
      stran = eps
      time = time + dt
    end do
    call expect(ok_stress, 'cycle: STRESS equals the C driver''s stress bit for bit')
    call expect(ok_tangent, 'cycle: DDSDDE(i, j) equals the C tangent[3 i + j] bit for bit')
    call expect(ok_counts, 'cycle: STATEV(2:3) are the RVE iterations and sub-steps')
    call expect(ok_id, 'cycle: STATEV(1) holds the point id, PNEWDT untouched or 0.5')
    call expect(asked < rows / 10, 'cycle: PNEWDT 0.5 on a few increments at most')
    write (*, '(a,i0,a,i0,a)') 'cycle: ', rows, ' increments (3 of them cut back, ', asked, &
        ' asking for PNEWDT 0.5) bit-identical to the C driver'
  end subroutine paper_cycle

  ! Part 2: NTENS = 4 and 6 on the plane-strain scene give one answer.
  subroutine layouts()
    real(real64) :: s4(4), d4(4, 4), s6(6), d6(6, 6), statev(3), pnewdt, time(2)
    real(real64) :: e4(4), e6(6), z4(4), z6(6), props(6)
    logical :: same
    integer :: i, j
    integer, parameter :: p(3) = [1, 2, 4]
    time = 0; z4 = 0; z6 = 0; props = 0
    e4 = [1.0e-4_real64, -2.0e-5_real64, 0.0_real64, 3.0e-5_real64]
    e6 = [e4, 0.0_real64, 0.0_real64]
    pnewdt = 1e36_real64
    call call_umat('@ABAQUS_RVE_UMAT@CONCRETE', 4, z4, e4, time, 1.0_real64, props, 101, 1, &
        s4, d4, statev, pnewdt)
    call call_umat('@ABAQUS_RVE_UMAT@CONCRETE', 6, z6, e6, time, 1.0_real64, props, 102, 1, &
        s6, d6, statev, pnewdt)
    call expect(pnewdt > 1, 'NTENS 4 and 6: no failure')
    same = all([(same_bits(s4(i), s6(i)), i = 1, 4)]) .and. same_bits(s6(5), 0.0_real64) .and. &
        same_bits(s6(6), 0.0_real64)
    do i = 1, 3
      do j = 1, 3
        same = same .and. same_bits(d4(p(i), p(j)), d6(p(i), p(j)))
      end do
      same = same .and. same_bits(d4(3, p(i)), d6(3, p(i))) .and. &
          same_bits(d4(3, p(i)), d4(p(i), 3))
    end do
    call expect(same, 'NTENS 4 and 6: one stress, one in-plane tangent, one s_zz row')
    call expect(abs(s4(3)) > 0.1_real64 * abs(s4(1)), 'plane strain: s_33 = s_zz /= 0')
    call expect(d6(3, 3) > 0 .and. d6(5, 5) > 0 .and. same_bits(d6(5, 5), d6(6, 6)) .and. &
        same_bits(d6(4, 5), 0.0_real64) .and. same_bits(d6(5, 1), 0.0_real64), 'NTENS 6: documented out-of-plane entries')
    write (*, '(a,es12.5,a,es12.5)') 'NTENS 4/6: s_11 = ', s4(1), ', s_33 = ', s4(3)
  end subroutine layouts

  ! Part 3: failures reach the host through PNEWDT, never a crash.
  subroutine errors()
    real(real64) :: s3(3), d3(3, 3), s6(6), d6(6, 6), statev(3), pnewdt, time(2)
    real(real64) :: e6(6), props(0)
    time = 0
    s3 = 7; pnewdt = 1e36_real64
    call call_umat('NO_SUCH_SCENE', 3, [0.0_real64, 0.0_real64, 0.0_real64], &
        [1.0e-5_real64, 0.0_real64, 0.0_real64], time, 1.0_real64, props, 201, 1, s3, d3, &
        statev, pnewdt)
    call expect(pnewdt < 1 .and. untouched(s3), 'missing scene: PNEWDT < 1, STRESS untouched')
    s6 = 7; pnewdt = 1e36_real64
    e6 = [1.0e-5_real64, 0.0_real64, 0.0_real64, 0.0_real64, 0.0_real64, 0.0_real64]
    call call_umat('PAPER_RVE', 6, 0 * e6, e6, time, 1.0_real64, props, 202, 1, s6, d6, &
        statev, pnewdt)
    call expect(pnewdt < 1 .and. untouched(s6), 'plane-stress scene under NTENS 6: PNEWDT')
    s6 = 7; pnewdt = 1e36_real64
    e6(5) = 1.0e-5_real64
    call call_umat('CONCRETE', 6, 0 * e6, e6, time, 1.0_real64, props, 203, 1, s6, d6, &
        statev, pnewdt)
    call expect(pnewdt < 1 .and. untouched(s6), 'gamma_13 /= 0 under NTENS 6: PNEWDT')
    s6 = 7; pnewdt = 1e36_real64
    call call_umat('CONCRETE', 5, 0 * e6(:5), e6(:5), time, 1.0_real64, props, 204, 1, &
        s6(:5), d6(:5, :5), statev, pnewdt)
    call expect(pnewdt < 1 .and. untouched(s6), 'NTENS 5: PNEWDT')
  end subroutine errors

end program umat_driver
